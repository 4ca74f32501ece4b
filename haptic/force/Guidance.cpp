// SPDX-License-Identifier: Apache-2.0
/// @file Guidance.cpp
/// @brief The guidance fixture (Guidance.h; physics.md §6.1, §6.2, §6.4).

#include "haptic/force/Guidance.h"

#include "core/Errors.h"

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

Guidance::Guidance(const GuidanceParams& p, const GuideLine& line) : mP(p), mLine(line)
{
    const Vec3d w = line.target - line.entry;
    if (!line.entry.allFinite() || !line.target.allFinite() || !(w.norm() > 1e-6))
        throw ValueError("guidance: the planned line's entry and target must be finite and distinct");
    mW = w / w.norm();
    if (!(p.stiffnessNPerMm >= 0.0) || !(p.maxForceN >= 0.0) || !(p.captureRadiusMm >= 0.0) || !(p.fadeOutS >= 0.0) ||
        !std::isfinite(p.stiffnessNPerMm + p.maxForceN + p.captureRadiusMm + p.fadeOutS))
        throw ValueError("guidance: stiffness, force, radius and fade-out must be finite and not negative");
}

Vec3d Guidance::offset(const Vec3d& tip) const noexcept
{
    const Vec3d r = tip - mLine.entry;
    return r - r.dot(mW) * mW;
}

double Guidance::profileN(double r) const noexcept
{
    if (!(r > 0.0)) return 0.0;
    double f = std::min(mP.stiffnessNPerMm * r, mP.maxForceN);
    const double R = mP.captureRadiusMm;
    if (R > 0.0 && r > R) f *= std::max(0.0, 2.0 - r / R); // 1 at R, 0 at 2R
    return f;
}

double Guidance::gain(double t) const noexcept
{
    if (!(mP.fadeOutS > 0.0) || !mStarted) return 1.0;
    return std::clamp(1.0 - (t - mStartS) / mP.fadeOutS, 0.0, 1.0);
}

double Guidance::stiffestNPerMm() const noexcept
{
    double k = mP.stiffnessNPerMm;
    if (mP.captureRadiusMm > 0.0) k = std::max(k, mP.maxForceN / mP.captureRadiusMm);
    return k;
}

Vec3d Guidance::update(const Vec3d& tip, double t) noexcept
{
    if (!tip.allFinite() || !std::isfinite(t)) return Vec3d::Zero();
    if (!mStarted) mStartS = t, mStarted = true;
    const Vec3d off = offset(tip);
    const double r = off.norm();
    if (!(r > 0.0)) return Vec3d::Zero(); // on the line: exactly nothing
    return -(gain(t) * profileN(r) / r) * off;
}

} // namespace voxhap::haptic
