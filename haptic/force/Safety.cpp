// SPDX-License-Identifier: Apache-2.0
/// @file Safety.cpp
/// @brief Passivity guard, clamping and rise limit (physics.md §6.2, §6.3, §6.4).

#include "haptic/force/Safety.h"

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

SafetyParams SafetyParams::fromDevice(const DeviceLimits& d)
{
    SafetyParams p;
    p.peakN = d.maxForceN;
    p.continuousN = std::min(d.maxContinuousForceN, d.maxForceN);
    return p;
}

void Safety::reset() noexcept
{
    mLast = mLastActive = Vec3d::Zero();
    mHavePoint = false;
    mFault = false;
    mEnergy = 0.0;
    mHeat = 0.0;
    mLimitedN = 0.0;
}

Vec3d Safety::apply(const Vec3d& force, const Vec3d& point, double dtS, const Vec3d& bias) noexcept
{
    const double dt = std::isfinite(dtS) && dtS > 0.0 ? std::min(dtS, mP.maxDtS) : 0.0;
    if (!force.allFinite() || !point.allFinite() || !bias.allFinite()) mFault = true;
    mLimitedN = 0.0;
    if (mFault) {
        mLast = mLastActive = Vec3d::Zero();
        mHavePoint = false;
        return mLast;
    }
    Vec3d f = force;
    // Passivity observer: the force held over the last tick did F·Δx of work on the
    // user. If the total turns positive, the controller adds just enough damping
    // along the latest motion to take it back over the next tick (Hannaford & Ryu 2002).
    if (mHavePoint) {
        const Vec3d dx = point - mLastPoint;
        mEnergy += mLastActive.dot(dx);
        const double dx2 = dx.squaredNorm();
        if (mP.passivity && mEnergy > 0.0 && dx2 > 1e-18) f -= (mEnergy / dx2) * dx;
    }
    f += bias;
    // Peak, then the continuous limit: an I²t budget that ramps the allowed force from
    // the peak down to the continuous force while the demand stays above it (§6.3).
    const double peak = mP.peakN, cont = std::min(mP.continuousN, mP.peakN);
    const double budget = std::max((peak * peak - cont * cont) * mP.peakBudgetS, 1e-12);
    const double allowed = cont + (peak - cont) * std::clamp(1.0 - mHeat / budget, 0.0, 1.0);
    mLimitedN = std::max(0.0, f.norm() - allowed);
    f = clampNorm(f, allowed);
    // Rise limit: the magnitude grows by at most riseNPerS·dt; a drop is immediate
    // (a pop, a critical structure or a fault must reach the hand at once).
    f = clampNorm(f, mLast.norm() + mP.riseNPerS * dt);
    const double n = f.norm();
    mHeat = std::clamp(mHeat + (n * n - cont * cont) * dt, 0.0, budget);
    mLast = f;
    mLastActive = f - bias;
    mLastPoint = point;
    mHavePoint = true;
    return f;
}

} // namespace voxhap::haptic
