// SPDX-License-Identifier: Apache-2.0
/// @file SimulatedDevice.h
/// @brief The stand-in for the hardware: what a haptic device's SDK gives an
/// application, shaped like the servo interfaces of OpenHaptics (a scheduler
/// callback), CHAI3D (the application's haptic thread) or a vendor's C driver.
/// The SDK owns the real-time thread and calls the application's function once
/// per period with the handle's state; the function fills in the force, which
/// the SDK sends to the motors. Nothing here knows voxhap.
///
/// Behind the handle is a trainee's hand instead of motors and encoders: a mass
/// held by a grip spring and damper to a set point that advances along a
/// straight line at a steady speed, pushed back by the rendered force.
#pragma once

#include <atomic>
#include <thread>

namespace simdev {

/// @brief The handle at one servo period, in the application's frame.
struct HandleState {
    double timeS = 0.0;              ///< the device's sample clock [s]: period × sample number
    double position[3] = {0, 0, 0};  ///< needle tip [mm]
    double velocity[3] = {0, 0, 0};  ///< [mm/s]
    double direction[3] = {0, 0, 1}; ///< needle axis, hub to tip (unit)
};

/// @brief Called on the device's servo thread once per period: read @p state, write
/// @p forceN, the force on the handle [N]. It must return within the period and must
/// not block.
using ServoCallback = void (*)(const HandleState& state, double forceN[3], void* user);

/// @brief The hand: where the needle's line is, and how the set point moves along it.
/// Defaults: a 0.3 kg hand and needle on a 1 N/mm grip, damped critically
/// (2·sqrt(k·m) = 0.035 N·s/mm), starting 5 mm before the line's origin.
struct Hand {
    double origin[3] = {0, 0, 0};    ///< [mm]
    double direction[3] = {0, 0, 1}; ///< unit
    double startMm = -5.0;           ///< the tip's first position on the line
    double speedMmPerS = 20.0;       ///< the set point's speed
    double gripNPerMm = 1.0;
    double dampingNsPerMm = 0.035;
    double massKg = 0.3;
};

class SimulatedDevice {
public:
    explicit SimulatedDevice(const Hand& hand, double rateHz = 1000.0);
    ~SimulatedDevice();
    SimulatedDevice(const SimulatedDevice&) = delete;
    SimulatedDevice& operator=(const SimulatedDevice&) = delete;

    /// @brief Start the servo thread: @p callback once per period until stop().
    void start(ServoCallback callback, void* user);
    void stop();
    /// @brief Periods served so far.
    long ticks() const noexcept { return mTicks.load(std::memory_order_relaxed); }
    /// @brief Periods that ended after their deadline (a loaded machine). The hand's
    /// time is the sample clock, so a late period changes the pace, not the physics.
    long late() const noexcept { return mLate.load(std::memory_order_relaxed); }

private:
    void run(ServoCallback callback, void* user) noexcept;

    Hand mHand;
    double mPeriodS;
    std::thread mThread;
    std::atomic<bool> mStop{false};
    std::atomic<long> mTicks{0}, mLate{0};
};

} // namespace simdev
