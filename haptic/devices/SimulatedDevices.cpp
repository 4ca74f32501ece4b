// SPDX-License-Identifier: Apache-2.0
/// @file SimulatedDevices.cpp
#include "haptic/devices/SimulatedDevices.h"

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

ScriptedDevice::ScriptedDevice(const NeedlePath& path, InsertionScript script, const DeviceLimits& limits)
    : mPath{path.origin, path.direction.normalized()}, mScript(std::move(script)), mLimits(limits)
{
}

DeviceReading ScriptedDevice::read(double t) noexcept
{
    mFinished = t > mScript.duration();
    DeviceReading r;
    r.tip = mPath.origin + mScript.depthAt(t) * mPath.direction;
    r.direction = mPath.direction;
    r.velocity = mScript.speedAt(t) * mPath.direction;
    r.rollRad = mScript.rollAt(t); // NaN for a script without a roll column
    r.valid = true;
    return r;
}

HandDevice::HandDevice(const NeedlePath& path, const HandParams& p, const DeviceLimits& limits)
    : mPath{path.origin, path.direction.normalized()}, mP(p), mLimits(limits), mX(p.startMm), mSet(p.startMm)
{
}

DeviceReading HandDevice::read(double) noexcept
{
    DeviceReading r;
    r.tip = mPath.origin + mX * mPath.direction;
    r.direction = mPath.direction;
    r.velocity = mV * mPath.direction;
    r.valid = true;
    r.plungerFraction = mEmptied;
    return r;
}

void HandDevice::write(const Vec3d& force, double plungerN, double t) noexcept
{
    const double dt = std::clamp(t - mT, 0.0, 0.01);
    mT = t;
    if (!(dt > 0.0)) return;
    // The hand feels the loss of resistance when the plunger, blocked before, gives way.
    mPeakPlunger = std::max(mPeakPlunger, std::isfinite(plungerN) ? plungerN : 0.0);
    if (mFeltAt < 0.0 && mPeakPlunger > mP.lorDropN && plungerN < mP.lorDropN) mFeltAt = t;
    if (mPeakPlunger >= mP.thumbForceN && std::isfinite(plungerN) && mP.thumbForceN > 0.0) {
        mEmptied = std::min(1.0, mEmptied + mP.emptyPerS * std::max(0.0, 1.0 - plungerN / mP.thumbForceN) * dt);
    }
    if (mP.stopOnLor && mFeltAt >= 0.0 && t - mFeltAt >= mP.reactionS) mStopped = true;
    if (!mStopped) mSet = std::min(mSet + mP.speedMmPerS * dt, mP.maxDepthMm);
    // m·a = grip·(set − x) − c·v + F·u, semi-implicit Euler in 10 sub-steps (stable for
    // the grip's 9 Hz and any device stiffness up to 10 N/mm at 1 kHz).
    const double fAxial = std::isfinite(force.dot(mPath.direction)) ? force.dot(mPath.direction) : 0.0;
    const double h = dt / 10.0, m = mP.massKg * 1e-3; // kg → N·s²/mm
    for (int i = 0; i < 10; ++i) {
        const double a = (mP.gripNPerMm * (mSet - mX) - mP.dampingNsPerMm * mV + fAxial) / m;
        mV += a * h;
        mX += mV * h;
    }
}

} // namespace voxhap::haptic
