// SPDX-License-Identifier: Apache-2.0
/// @file IgtlDevice.cpp
/// @brief OpenIGTLink server: bounded, validated reads; TRANSFORM in, SENSOR and STRING out.

#include "haptic/IgtlDevice.h"

#include "volume/Errors.h"

#include <igtlSensorMessage.h>
#include <igtlStringMessage.h>
#include <igtlTransformMessage.h>
#include <igtlUnit.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <sstream>
#include <vector>

namespace voxhap::haptic {

namespace {

constexpr std::size_t kHeaderBytes = 58; // OpenIGTLink v1/v2 header
constexpr std::uint64_t kTransformBodyBytes = 48;

double wallS()
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::uint64_t bigEndian64(const unsigned char* p)
{
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v = (v << 8) | p[i];
    return v;
}

/// Read exactly @p n bytes within @p timeoutS; false on timeout, error or close.
bool readExactly(int fd, unsigned char* buf, std::size_t n, double timeoutS)
{
    const double end = wallS() + timeoutS;
    std::size_t got = 0;
    while (got < n) {
        const double left = end - wallS();
        if (left <= 0.0) return false;
        pollfd p{fd, POLLIN, 0};
        if (::poll(&p, 1, int(std::ceil(left * 1000.0))) <= 0) return false;
        const ssize_t r = ::recv(fd, buf + got, n - got, 0);
        if (r <= 0) return false;
        got += std::size_t(r);
    }
    return true;
}

/// Send without blocking the network thread for long: a client that does not read
/// (the Debian tracker example) fills its buffer and then misses replies.
bool sendAll(int fd, const void* data, std::size_t n)
{
    const ssize_t r = ::send(fd, data, n, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (r == ssize_t(n)) return true;
    return r < 0 && (errno == EAGAIN || errno == EWOULDBLOCK); // full: skip this one, keep the link
}

} // namespace

IgtlDevice::IgtlDevice(const IgtlOptions& options, const DeviceLimits& limits) : mOpt(options), mLimits(limits)
{
    mListen = ::socket(AF_INET, SOCK_STREAM, 0);
    if (mListen < 0) throw IoError("igtl: cannot create a socket: " + std::string(std::strerror(errno)));
    const int one = 1;
    ::setsockopt(mListen, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(std::uint16_t(mOpt.port));
    if (::inet_pton(AF_INET, mOpt.bindAddress.c_str(), &addr.sin_addr) != 1) {
        ::close(mListen);
        throw IoError("igtl: bad bind address '" + mOpt.bindAddress + "'");
    }
    if (::bind(mListen, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 || ::listen(mListen, 1) != 0) {
        const std::string why = std::strerror(errno);
        ::close(mListen);
        throw IoError("igtl: cannot listen on " + mOpt.bindAddress + ":" + std::to_string(mOpt.port) + ": " + why);
    }
    socklen_t len = sizeof addr;
    ::getsockname(mListen, reinterpret_cast<sockaddr*>(&addr), &len);
    mPort = ntohs(addr.sin_port);
    mDir[2].store(1.0);
    mThread = std::thread([this] { serve(); });
}

IgtlDevice::~IgtlDevice()
{
    mStop.store(true);
    if (mThread.joinable()) mThread.join();
    if (mListen >= 0) ::close(mListen);
}

DeviceReading IgtlDevice::read(double) noexcept
{
    DeviceReading r; // the last pose received, whether or not it is still current
    const bool connected = mConnected.load(std::memory_order_acquire);
    r.lost = !connected && mCounters.connections.load() > 0; // a client came and went: zero at once
    for (int i = 0; i < 3; ++i) {
        r.tip[i] = mTip[i].load(std::memory_order_relaxed);
        r.direction[i] = mDir[i].load(std::memory_order_relaxed);
        r.velocity[i] = mVel[i].load(std::memory_order_relaxed);
    }
    const double at = mPoseWallS.load(std::memory_order_acquire);
    r.valid = connected && at >= 0.0 && wallS() - at <= mOpt.staleS;
    return r;
}

void IgtlDevice::write(const Vec3d& f, double, double) noexcept
{
    for (int i = 0; i < 3; ++i) mForce[i].store(std::isfinite(f[i]) ? f[i] : 0.0, std::memory_order_relaxed);
}

void IgtlDevice::sendForce(int fd) noexcept
{
    try { // the library allocates; this is the network thread, not the servo
        auto msg = igtl::SensorMessage::New();
        msg->SetDeviceName("voxhap-force");
        msg->SetLength(3);
        auto unit = igtl::Unit::New();
        unit->Init();
        unit->SetPrefix(igtl::Unit::SI_PREFIX_NONE);
        unit->Append(igtl::Unit::SI_DERIVED_NEWTON, 1);
        msg->SetUnit(unit);
        for (unsigned i = 0; i < 3; ++i) msg->SetValue(i, mForce[i].load(std::memory_order_relaxed));
        msg->Pack();
        if (sendAll(fd, msg->GetPackPointer(), std::size_t(msg->GetPackSize()))) mCounters.forcesSent.fetch_add(1);
    } catch (...) {
    }
}

void IgtlDevice::sendEvents(int fd) noexcept
{
    Event e;
    while (mEvents.pop(e)) {
        try {
            std::ostringstream text;
            text << eventName(e.type) << " t=" << std::fixed << std::setprecision(3) << e.timeS << "s depth="
                 << std::setprecision(2) << e.depthMm << "mm layer=" << e.layer;
            auto msg = igtl::StringMessage::New();
            msg->SetDeviceName("voxhap-event");
            msg->SetString(text.str().c_str());
            msg->Pack();
            if (sendAll(fd, msg->GetPackPointer(), std::size_t(msg->GetPackSize()))) mCounters.eventsSent.fetch_add(1);
        } catch (...) {
        }
    }
}

bool IgtlDevice::handleMessage(int fd) noexcept
{
    unsigned char header[kHeaderBytes];
    if (!readExactly(fd, header, kHeaderBytes, mOpt.receiveTimeoutS)) return false;
    const unsigned version = (unsigned(header[0]) << 8) | header[1];
    char type[13] = {};
    std::memcpy(type, header + 2, 12);
    const std::uint64_t bodySize = bigEndian64(header + 42);
    const auto reject = [this] {
        mCounters.rejected.fetch_add(1);
        return false;
    };
    // Check before allocating anything (toolchain.md): version, size limit, exact TRANSFORM size.
    if (version < 1 || version > 2 || bodySize > mOpt.maxBodyBytes) return reject();
    const bool transform = std::strncmp(type, "TRANSFORM", 12) == 0;
    if (transform && (version == 1 ? bodySize != kTransformBodyBytes : bodySize < kTransformBodyBytes)) return reject();
    try {
        auto head = igtl::MessageHeader::New();
        head->InitPack();
        std::memcpy(head->GetPackPointer(), header, kHeaderBytes);
        head->Unpack(); // byte-swaps in place
        if (!transform) { // read and discard, bounded
            std::vector<unsigned char> body(bodySize);
            return bodySize == 0 || readExactly(fd, body.data(), body.size(), mOpt.receiveTimeoutS);
        }
        auto msg = igtl::TransformMessage::New();
        msg->SetMessageHeader(head);
        msg->AllocatePack();
        if (std::uint64_t(msg->GetPackBodySize()) != bodySize) return reject();
        if (!readExactly(fd, static_cast<unsigned char*>(msg->GetPackBodyPointer()), bodySize, mOpt.receiveTimeoutS)) {
            return false;
        }
        if (!(msg->Unpack(1) & igtl::MessageHeader::UNPACK_BODY)) return reject(); // CRC mismatch
        igtl::Matrix4x4 m;
        msg->GetMatrix(m);
        const Vec3d tip(m[0][3], m[1][3], m[2][3]);
        Vec3d dir(m[0][2], m[1][2], m[2][2]);
        if (!tip.allFinite() || !dir.allFinite() || !(dir.norm() > 1e-6)) {
            mCounters.rejected.fetch_add(1);
            return true; // a bad pose, not a broken stream: ignore it
        }
        dir.normalize();
        const double now = wallS();
        const double before = mPoseWallS.load();
        Vec3d vel = Vec3d::Zero();
        if (before >= 0.0 && now - before > 1e-4) {
            const Vec3d last(mTip[0].load(), mTip[1].load(), mTip[2].load());
            vel = (tip - last) / (now - before);
        }
        for (int i = 0; i < 3; ++i) {
            mTip[i].store(tip[i], std::memory_order_relaxed);
            mDir[i].store(dir[i], std::memory_order_relaxed);
            mVel[i].store(vel[i], std::memory_order_relaxed);
        }
        mPoseWallS.store(now, std::memory_order_release);
        mCounters.poses.fetch_add(1);
        sendForce(fd); // answer each pose with the latest force
        return true;
    } catch (...) {
        return false;
    }
}

void IgtlDevice::serve() noexcept
{
    int client = -1;
    while (!mStop.load()) {
        pollfd fds[2] = {{mListen, POLLIN, 0}, {client, POLLIN, 0}};
        const int n = ::poll(fds, client >= 0 ? 2 : 1, 10);
        if (n < 0 && errno != EINTR) break;
        if (fds[0].revents & POLLIN) {
            const int c = ::accept(mListen, nullptr, nullptr);
            if (c >= 0 && client >= 0) {
                ::close(c); // one client at a time
            } else if (c >= 0) {
                const int one = 1;
                ::setsockopt(c, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
                client = c;
                mPoseWallS.store(-1.0);
                mConnected.store(true, std::memory_order_release);
                mCounters.connections.fetch_add(1);
            }
        }
        if (client >= 0) {
            bool ok = true;
            if (fds[1].revents & (POLLIN | POLLHUP | POLLERR)) ok = handleMessage(client);
            if (ok) sendEvents(client);
            if (!ok) {
                mConnected.store(false, std::memory_order_release);
                ::close(client);
                client = -1;
                mCounters.disconnects.fetch_add(1);
            }
        }
    }
    if (client >= 0) ::close(client);
}

} // namespace voxhap::haptic
