// SPDX-License-Identifier: Apache-2.0
/// @file IgtlDevice.h
/// @brief The OpenIGTLink bridge (architecture.md "Devices"): a TCP server,
/// loopback by default on port 18944, that receives the needle pose as TRANSFORM
/// messages, answers each with the force as a SENSOR message in newtons and
/// streams insertion events as STRING messages, so that any tracker driver or
/// 3D Slicer can drive voxhap.
///
/// Pose convention [chosen]: the transform's translation is the needle tip [mm,
/// LPS] and its third column (the tool's z axis) the needle direction, hub to tip.
///
/// The library trusts message headers (toolchain.md "OpenIGTLink facts"), so the
/// server checks the raw header first — version, body size against a limit, the
/// exact size of a TRANSFORM body — reads bodies with a timeout, checks the CRC,
/// and drops the connection on any violation. One client at a time. The servo
/// thread never waits on the network: poses and forces cross in atomics, events
/// in a lock-free queue.
#pragma once

#include "haptic/Events.h"
#include "haptic/servo/Device.h"
#include "haptic/servo/SpscQueue.h"

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

namespace voxhap::haptic {

struct IgtlOptions {
    int port = 18944; ///< 0: any free port (tests)
    std::string bindAddress = "127.0.0.1";
    std::uint64_t maxBodyBytes = 65536; ///< larger bodies drop the connection
    double receiveTimeoutS = 0.5;       ///< a message must arrive whole within this
    double staleS = 0.050;              ///< a pose older than this is not valid [chosen]
    /// Connection policy: one controlling client. A new connection must send its
    /// first message within firstMessageS; a client silent for idleS is dropped;
    /// a newcomer replaces a client silent for replaceSilentS, and is refused
    /// (closed) otherwise. Dropping the client zeroes the force at once.
    double firstMessageS = 2.0;   ///< [chosen]: a tracker sends its first pose at once
    double idleS = 5.0;           ///< [chosen]
    double replaceSilentS = 0.25; ///< [chosen]: five times the staleness
    /// The clock of the timeouts and of pose ages [s]; null: the steady clock
    /// (tests pass a simulated one).
    double (*clock)() = nullptr;
};

/// @brief Counters for tests and the status line (all updated by the network thread).
struct IgtlCounters {
    std::atomic<long> connections{0}, disconnects{0}, poses{0}, forcesSent{0}, eventsSent{0}, rejected{0};
    std::atomic<long> timeouts{0}; ///< clients dropped for silence (first message or idle)
    std::atomic<long> refused{0};  ///< newcomers closed while a live client controls the device
    std::atomic<long> replaced{0}; ///< silent clients replaced by a newcomer
};

class IgtlDevice final : public Device {
public:
    /// @throw IoError if the address cannot be bound (port in use, bad address)
    IgtlDevice(const IgtlOptions& options, const DeviceLimits& limits);
    ~IgtlDevice() override;
    IgtlDevice(const IgtlDevice&) = delete;
    IgtlDevice& operator=(const IgtlDevice&) = delete;

    DeviceReading read(double timeS) noexcept override;
    void write(const Vec3d& forceN, double plungerN, double timeS) noexcept override;
    void event(const Event& e) noexcept override { mEvents.push(e); }
    const DeviceLimits& limits() const noexcept override { return mLimits; }
    std::string name() const override { return "igtl:" + std::to_string(mPort); }

    int port() const noexcept { return mPort; }
    const IgtlCounters& counters() const noexcept { return mCounters; }
    bool connected() const noexcept { return mConnected.load(); }

private:
    void serve() noexcept;
    bool handleMessage(int fd) noexcept; ///< false: drop the connection
    void sendForce(int fd) noexcept;
    void sendEvents(int fd) noexcept;
    double now() const noexcept;

    IgtlOptions mOpt;
    DeviceLimits mLimits;
    int mListen = -1;
    int mPort = 0;
    std::thread mThread;
    std::atomic<bool> mStop{false}, mConnected{false};
    // The latest pose (written by the network thread) and force (by the servo thread).
    std::atomic<double> mTip[3]{}, mDir[3]{}, mVel[3]{}, mForce[3]{};
    std::atomic<double> mPoseWallS{-1.0};
    std::atomic<long> mPoseCount{0};
    SpscQueue<Event, 256> mEvents;
    IgtlCounters mCounters;
};

/// @brief Make "igtl[:PORT]" known to parseDeviceSpec() and makeDevice()
/// (haptic/devices/DeviceSpec.h): the server on 127.0.0.1, on PORT (1..65535)
/// or the default 18944. Programs built with voxhap::igtl call it once at
/// start-up (DeviceSpec.h says why it is not a static initialiser).
void registerIgtlDevice();

} // namespace voxhap::haptic
