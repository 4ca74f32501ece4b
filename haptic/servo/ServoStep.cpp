// SPDX-License-Identifier: Apache-2.0
/// @file ServoStep.cpp
#include "haptic/servo/ServoStep.h"

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

ServoStep::ServoStep(NeedleForceModel& model, const ServoStepOptions& options) : mModel(model), mOpt(options)
{
    if (!(mOpt.rateHz > 0.0) || !std::isfinite(mOpt.rateHz)) mOpt.rateHz = 1000.0;
}

Vec3d ServoStep::step(const DeviceReading& reading, double timeS) noexcept
{
    const double nominal = 1.0 / mOpt.rateHz;
    // A clock that stands still, runs back or is not a number gives no period to
    // judge: take the nominal one (a non-finite time also latches the model's fault).
    const double measured = timeS - mLastTimeS;
    const double period = mFirst || !(measured > 0.0) || !std::isfinite(measured) ? nominal : measured;
    return step(reading, timeS, nominal, period);
}

Vec3d ServoStep::step(const DeviceReading& r, double t, double dt, double period) noexcept
{
    mFirst = false;
    mLastTimeS = t;
    Vec3d target = mLastForce;
    if (r.valid) {
        mQuietS = r.poseAgeS; // an aging network pose is quiet time already spent
        NeedleInput in;
        in.timeS = t;
        in.dtS = dt;
        in.tip = r.tip;
        in.direction = r.direction;
        in.velocity = r.velocity;
        in.rollRad = r.rollRad;
        mModel.step(in, mOut);
        target = mOut.force;
    } else {
        mQuietS += dt;
        mOut.events.clear(); // the last tick's events are not this one's
    }
    // Watchdog (physics.md §6.3): a quiet device ramps the force to zero, a stalled
    // loop cuts it in proportion to the stall; it comes back the same way.
    constexpr double kTimeTolS = 1e-9; // sums of tick periods carry round-off
    const bool stalled = mQuietS > mOpt.watchdogS + kTimeTolS || period > mOpt.watchdogS + kTimeTolS;
    const double step = mOpt.rampS > 0.0 ? std::max(dt, period) / mOpt.rampS : 1.0;
    const bool releasing = mReleasing.load(std::memory_order_relaxed);
    mGain = r.lost ? 0.0 : stalled || releasing ? std::max(0.0, mGain - step) : std::min(1.0, mGain + step);
    mLastForce = target;
    // A release ends on the tick that sends zero.
    if (releasing && mGain == 0.0) mReleased.store(true, std::memory_order_relaxed);
    return mGain * target;
}

} // namespace voxhap::haptic
