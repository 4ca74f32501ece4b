// SPDX-License-Identifier: Apache-2.0
/// @file ReplayDevice.cpp
#include "haptic/devices/ReplayDevice.h"

#include "core/Errors.h"

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

ReplayDevice::ReplayDevice(std::vector<ServoRecord> poses, const DeviceLimits& limits)
    : mPoses(std::move(poses)), mLimits(limits)
{
    if (mPoses.size() < 2) throw ValueError("replay: a session needs at least two records");
}

DeviceReading ReplayDevice::read(double t) noexcept
{
    const double t0 = mPoses.front().timeS;
    const double tt = t + t0;
    while (mIndex + 2 < mPoses.size() && mPoses[mIndex + 1].timeS <= tt) ++mIndex;
    mFinished = tt > mPoses.back().timeS;
    const ServoRecord& a = mPoses[mIndex];
    const ServoRecord& b = mPoses[mIndex + 1];
    const double w = std::clamp((tt - a.timeS) / (b.timeS - a.timeS), 0.0, 1.0);
    DeviceReading r;
    r.tip = a.tip + w * (b.tip - a.tip);
    const Vec3d d = a.direction + w * (b.direction - a.direction);
    r.direction = d.norm() > 0.0 ? Vec3d(d.normalized()) : a.direction;
    r.velocity = (b.tip - a.tip) / (b.timeS - a.timeS);
    // The roll, where the session has one (a device that senses none recorded NaN).
    r.rollRad =
        std::isfinite(a.rollRad) && std::isfinite(b.rollRad) ? a.rollRad + w * (b.rollRad - a.rollRad) : a.rollRad;
    r.valid = true;
    return r;
}

} // namespace voxhap::haptic
