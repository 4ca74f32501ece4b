// SPDX-License-Identifier: Apache-2.0
/// @file ServoStep.h
/// @brief One servo tick without a thread or a Device (architecture.md "Threads"):
/// the force model's step and the watchdog of physics.md §6.3. For code that
/// already owns a real-time loop, such as a device SDK's servo callback
/// (examples/device-loop/), and for ServoLoop, which calls it from its own
/// thread. step() never allocates, locks, throws or logs.
#pragma once

#include "haptic/force/NeedleForceModel.h"
#include "haptic/servo/Device.h"

#include <atomic>

namespace voxhap::haptic {

struct ServoStepOptions {
    /// The nominal tick rate: the model integrates over 1/rateHz on every tick, so a
    /// late tick does not change the physics, only the watchdog sees it.
    double rateHz = 1000.0;
    /// Watchdog (physics.md §6.3) [chosen], as ServoOptions describes it: quiet longer
    /// than watchdogS, or a period longer than watchdogS, ramps the gain on the force
    /// down by period/rampS per tick; otherwise it ramps back up to 1.
    double watchdogS = 0.020; ///< [s]
    double rampS = 0.050;     ///< [s]
};

class ServoStep {
public:
    /// @param model the force model this tick steps; it must outlive the ServoStep
    explicit ServoStep(NeedleForceModel& model, const ServoStepOptions& options = {});

    /// @brief One tick of the caller's loop at @p timeS, the caller's monotonic clock
    /// [s]; the period since the previous tick is the difference of the times (the
    /// nominal period on the first tick). @return the force to send to the device [N]
    Vec3d step(const DeviceReading& reading, double timeS) noexcept;
    /// @brief One tick with its periods given: the model steps by @p dtS and the
    /// watchdog counts @p periodS, the time since the previous tick [s].
    Vec3d step(const DeviceReading& reading, double timeS, double dtS, double periodS) noexcept;

    /// @brief The model's output of the last tick whose reading was valid; its events
    /// are this tick's (none after a quiet tick).
    const NeedleOutput& output() const noexcept { return mOut; }
    /// @brief The watchdog's gain on the model force, 0..1, after the last tick.
    double gain() const noexcept { return mGain; }
    /// @brief Ramp the force to zero at the watchdog's rate, whatever the device does
    /// (a Ctrl-C or SIGTERM; physics.md §6.3). Any thread may call it.
    void beginRelease() noexcept { mReleasing.store(true, std::memory_order_relaxed); }
    bool releasing() const noexcept { return mReleasing.load(std::memory_order_relaxed); }
    /// @brief A release has sent its zero force: the caller may stop its loop.
    bool released() const noexcept { return mReleased.load(std::memory_order_relaxed); }
    const ServoStepOptions& options() const noexcept { return mOpt; }
    NeedleForceModel& model() noexcept { return mModel; }

private:
    NeedleForceModel& mModel;
    ServoStepOptions mOpt;
    NeedleOutput mOut;
    double mGain = 1.0, mQuietS = 0.0, mLastTimeS = 0.0;
    bool mFirst = true;
    Vec3d mLastForce{0, 0, 0};
    std::atomic<bool> mReleasing{false}, mReleased{false};
};

} // namespace voxhap::haptic
