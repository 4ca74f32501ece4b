// SPDX-License-Identifier: Apache-2.0
/// @file PoseStream.cpp
/// @brief TRANSFORM out (a reconnecting client) and in (a validating one-client server).

#include "haptic/igtl/PoseStream.h"

#include "haptic/igtl/detail/IgtlWire.h"

#include "core/Errors.h"

#include <igtlPointMessage.h>
#include <igtlTransformMessage.h>

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <Eigen/Geometry> // for cross and unitOrthogonal

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <vector>

namespace voxhap::haptic {

namespace {

constexpr std::uint64_t kPoseMaxBodyBytes = 65536; // larger bodies drop the connection
constexpr double kPoseReadTimeoutS = 0.5;          // a message must arrive whole within this
constexpr int kPoseConnectTimeoutMs = 200;         // a viewer on loopback or a LAN answers far sooner

} // namespace

void parseHostPort(const std::string& text, const std::string& what, std::string& host, int& port)
{
    const auto colon = text.rfind(':');
    host = colon == std::string::npos ? "127.0.0.1" : text.substr(0, colon);
    const std::string p = colon == std::string::npos ? text : text.substr(colon + 1);
    if (host.empty()) throw ValueError(what + ": '" + text + "': empty host");
    std::size_t used = 0;
    long v = -1;
    try {
        v = std::stol(p, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used == 0 || used != p.size() || v < 1 || v > 65535) {
        throw ValueError(what + ": '" + text + "': the port must be a number in 1..65535");
    }
    port = int(v);
    in_addr a{};
    if (::inet_pton(AF_INET, host.c_str(), &a) != 1) {
        throw ValueError(what + ": '" + host + "' is not an IPv4 address");
    }
}

// ---------------------------------------------------------------------------
// PoseSender

PoseSender::PoseSender(std::string host, int port, double retryS) : mHost(std::move(host)), mPort(port), mRetryS(retryS)
{
    in_addr a{};
    if (::inet_pton(AF_INET, mHost.c_str(), &a) != 1)
        throw ValueError("pose stream: '" + mHost + "' is not an IPv4 address");
}

PoseSender::~PoseSender()
{
    if (mFd >= 0) ::close(mFd);
}

bool PoseSender::connectNow()
{
    const double now = detail::steadySeconds();
    if (now - mLastAttemptS < mRetryS) return false;
    mLastAttemptS = now;
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0) return false;
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(std::uint16_t(mPort));
    ::inet_pton(AF_INET, mHost.c_str(), &a.sin_addr);
    // Non-blocking connect with a short timeout: a missing viewer must not stall the caller.
    ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL, 0) | O_NONBLOCK);
    int rc = ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
    if (rc != 0 && errno == EINPROGRESS) {
        pollfd p{fd, POLLOUT, 0};
        int err = 0;
        socklen_t len = sizeof err;
        rc = ::poll(&p, 1, kPoseConnectTimeoutMs) == 1 && ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len) == 0 &&
                err == 0
            ? 0
            : -1;
    }
    if (rc != 0) {
        ::close(fd);
        return false;
    }
    const int one = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    mFd = fd;
    return true;
}

bool PoseSender::send(const StreamedPose& pose)
{
    if (mFd < 0 && !connectNow()) return false;
    const Vec3d z = pose.direction.normalized(), x = z.unitOrthogonal(), y = z.cross(x);
    auto msg = igtl::TransformMessage::New();
    msg->SetDeviceName("voxhap-needle");
    igtl::Matrix4x4 m;
    igtl::IdentityMatrix(m);
    for (int i = 0; i < 3; ++i) {
        m[i][0] = float(x[i]), m[i][1] = float(y[i]), m[i][2] = float(z[i]);
        m[i][3] = float(pose.tip[i]);
    }
    msg->SetMatrix(m);
    msg->Pack();
    // One send for the shaft and the pose: a dropped write drops both, never half.
    std::vector<unsigned char> wire;
    if (!pose.shaft.empty()) {
        auto points = igtl::PointMessage::New();
        points->SetDeviceName(detail::kShaftDeviceName);
        for (const Vec3d& q : pose.shaft) {
            auto e = igtl::PointElement::New();
            e->SetName("shaft");
            e->SetGroupName("Needle");
            e->SetPosition(float(q.x()), float(q.y()), float(q.z()));
            points->AddPointElement(e);
        }
        points->Pack();
        const auto* bytes = static_cast<const unsigned char*>(points->GetPackPointer());
        wire.assign(bytes, bytes + points->GetPackSize());
    }
    const auto* bytes = static_cast<const unsigned char*>(msg->GetPackPointer());
    wire.insert(wire.end(), bytes, bytes + msg->GetPackSize());
    const std::size_t n = wire.size();
    const ssize_t r = ::send(mFd, wire.data(), n, MSG_NOSIGNAL);
    if (r == ssize_t(n)) {
        ++mSent;
        return true;
    }
    if (r < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return false; // viewer busy: drop this pose
    ::close(mFd); // lost, or a partial message that would desynchronise the stream: reconnect later
    mFd = -1;
    return false;
}

// ---------------------------------------------------------------------------
// PoseReceiver

PoseReceiver::PoseReceiver(int port, const std::string& bindAddress)
{
    mListen = detail::listenTcp(bindAddress, port, "pose stream", mPort);
    mThread = std::thread([this] { serve(); });
}

PoseReceiver::~PoseReceiver()
{
    mStop.store(true);
    if (mThread.joinable()) mThread.join();
    if (mListen >= 0) ::close(mListen);
}

std::optional<StreamedPose> PoseReceiver::latest() const
{
    std::lock_guard<std::mutex> lock(mMutex);
    return mLatest;
}

bool PoseReceiver::handleMessage(int fd) noexcept
{
    StreamedPose p;
    std::vector<Vec3d> shaft;
    switch (detail::readTransform(fd, kPoseReadTimeoutS, kPoseMaxBodyBytes, p.tip, p.direction, &shaft)) {
    case detail::WireRead::Broken:
        return false;
    case detail::WireRead::BadHeader:
        mRejected.fetch_add(1);
        return false;
    case detail::WireRead::BadPose:
        mRejected.fetch_add(1);
        mPendingShaft.clear(); // a bad shaft or pose: the next pose is drawn straight, not with a stale shaft
        return true;           // a bad pose, not a broken stream
    case detail::WireRead::Skipped:
        return true;
    case detail::WireRead::Shaft:
        mPendingShaft = std::move(shaft);
        return true;
    case detail::WireRead::Pose:
        break;
    }
    try {
        p.shaft = std::move(mPendingShaft); // the shaft sent just before, if any
        mPendingShaft.clear();
        const double norm = p.direction.norm();
        // A unit column arrives unit to float precision; keep it as sent then,
        // so that the receiver returns exactly the float values on the wire.
        if (std::abs(norm - 1.0) > 1e-5) p.direction /= norm;
        {
            std::lock_guard<std::mutex> lock(mMutex);
            mLatest = p;
        }
        mPoses.fetch_add(1);
        return true;
    } catch (...) {
        return false;
    }
}

void PoseReceiver::serve() noexcept
{
    int client = -1;
    while (!mStop.load()) {
        pollfd fds[2] = {{mListen, POLLIN, 0}, {client, POLLIN, 0}};
        const int n = ::poll(fds, client >= 0 ? 2 : 1, 10);
        if (n < 0 && errno != EINTR) break;
        if (fds[0].revents & POLLIN) {
            const int c = ::accept(mListen, nullptr, nullptr);
            if (c >= 0 && client >= 0) {
                ::close(c); // one sender at a time
            } else if (c >= 0) {
                client = c;
                mPendingShaft.clear(); // a shaft belongs to the connection that sent it
                mConnected.store(true);
            }
        }
        if (client >= 0 && (fds[1].revents & (POLLIN | POLLHUP | POLLERR))) {
            if (!handleMessage(client)) {
                ::close(client);
                client = -1;
                mConnected.store(false);
            }
        }
    }
    if (client >= 0) ::close(client);
}

} // namespace voxhap::haptic
