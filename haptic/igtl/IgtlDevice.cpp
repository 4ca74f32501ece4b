// SPDX-License-Identifier: Apache-2.0
/// @file IgtlDevice.cpp
/// @brief OpenIGTLink server: bounded, validated reads; TRANSFORM in, SENSOR and STRING out.

#include "haptic/igtl/IgtlDevice.h"

#include "haptic/igtl/detail/IgtlWire.h"

#include "core/Errors.h"
#include "haptic/devices/DeviceSpec.h"

#include <igtlSensorMessage.h>
#include <igtlStringMessage.h>
#include <igtlUnit.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <sstream>
#include <vector>

namespace voxhap::haptic {

namespace {

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
    mListen = detail::listenTcp(mOpt.bindAddress, mOpt.port, "igtl", mPort);
    mDir[2].store(1.0);
    mThread = std::thread([this] { serve(); });
}

IgtlDevice::~IgtlDevice()
{
    mStop.store(true);
    if (mThread.joinable()) mThread.join();
    if (mListen >= 0) ::close(mListen);
}

double IgtlDevice::now() const noexcept { return mOpt.clock ? mOpt.clock() : detail::steadySeconds(); }

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
    const double age = at >= 0.0 ? now() - at : 0.0;
    r.valid = connected && at >= 0.0 && age <= mOpt.staleS;
    r.poseAgeS = std::max(0.0, age);
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
            text << eventName(e.type) << " t=" << std::fixed << std::setprecision(3) << e.timeS
                 << "s depth=" << std::setprecision(2) << e.depthMm << "mm layer=" << e.layer;
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
    Vec3d tip, dir;
    switch (detail::readTransform(fd, mOpt.receiveTimeoutS, mOpt.maxBodyBytes, tip, dir)) {
    case detail::WireRead::Broken:
        return false;
    case detail::WireRead::BadHeader:
        mCounters.rejected.fetch_add(1);
        return false;
    case detail::WireRead::BadPose:
        mCounters.rejected.fetch_add(1);
        return true; // a bad pose, not a broken stream
    case detail::WireRead::Skipped:
    case detail::WireRead::Shaft: // not asked for (no shaft buffer): a POINT is skipped
        return true;
    case detail::WireRead::Pose:
        break;
    }
    dir.normalize();
    const double now = this->now();
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
}

void IgtlDevice::serve() noexcept
{
    int client = -1;
    double heard = 0.0; // when the client last sent a message (or connected)
    bool spoke = false; // it has sent one
    const auto drop = [&] {
        mConnected.store(false, std::memory_order_release);
        ::close(client);
        client = -1;
        mCounters.disconnects.fetch_add(1);
    };
    const auto adopt = [&](int c) {
        const int one = 1;
        ::setsockopt(c, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        client = c;
        heard = now();
        spoke = false;
        mPoseWallS.store(-1.0);
        mConnected.store(true, std::memory_order_release);
        mCounters.connections.fetch_add(1);
    };
    while (!mStop.load()) {
        pollfd fds[2] = {{mListen, POLLIN, 0}, {client, POLLIN, 0}};
        const int n = ::poll(fds, client >= 0 ? 2 : 1, 10);
        if (n < 0 && errno != EINTR) break;
        if (fds[0].revents & POLLIN) {
            const int c = ::accept(mListen, nullptr, nullptr);
            if (c >= 0 && client >= 0 && now() - heard > mOpt.replaceSilentS) {
                drop(); // a silent client gives way to a newcomer
                mCounters.replaced.fetch_add(1);
                adopt(c);
            } else if (c >= 0 && client >= 0) {
                ::close(c); // one controlling client, and it is alive
                mCounters.refused.fetch_add(1);
            } else if (c >= 0) {
                adopt(c);
            }
        }
        if (client >= 0) {
            bool ok = true;
            if (fds[1].revents & (POLLIN | POLLHUP | POLLERR)) {
                ok = handleMessage(client);
                heard = now();
                spoke = true;
            }
            if (ok) sendEvents(client);
            // Silence: no first message in time, or none for idleS since the last.
            if (ok && now() - heard > (spoke ? mOpt.idleS : mOpt.firstMessageS)) {
                ok = false;
                mCounters.timeouts.fetch_add(1);
            }
            if (!ok) drop();
        }
    }
    if (client >= 0) ::close(client);
}

void registerIgtlDevice()
{
    DeviceKind kind;
    kind.name = "igtl";
    kind.usage = "igtl[:PORT]";
    kind.check = [](DeviceSpec& s) {
        if (s.text.find(':') == std::string::npos) return;
        const std::string& port = s.argument;
        // Digits only: "28945junk" or "+80" is a typo, not a port (std::stoi took its prefix).
        if (port.empty() || port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos)
            throw ValueError("device '" + s.text + "': the port must be a number in 1..65535");
        const int n = std::stoi(port);
        if (n < 1 || n > 65535) throw ValueError("device '" + s.text + "': port " + port + " outside 1..65535");
    };
    kind.make = [](const DeviceSpec& s, const DeviceContext& c) {
        IgtlOptions o;
        if (!s.argument.empty()) o.port = std::stoi(s.argument);
        auto device = std::make_unique<IgtlDevice>(o, c.limits);
        if (c.announce) {
            c.announce("OpenIGTLink server on " + o.bindAddress + ":" + std::to_string(device->port()) +
                " (TRANSFORM in: tip = translation, needle = z axis; SENSOR force out, in N)");
        }
        return std::unique_ptr<Device>(std::move(device));
    };
    registerDeviceKind(std::move(kind));
}

} // namespace voxhap::haptic
