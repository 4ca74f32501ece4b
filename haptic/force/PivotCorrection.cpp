// SPDX-License-Identifier: Apache-2.0
/// @file PivotCorrection.cpp
/// @brief Layered Kelvin correction about the pivot (physics.md §1.4).

#include "haptic/force/PivotCorrection.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace voxhap::haptic {

double KelvinElement::step(double x, double period) noexcept
{
    if (!std::isfinite(x)) return mF;
    const double t = (period > 0.0 && std::isfinite(period)) ? period : std::numeric_limits<double>::min();
    const double b = mTau * mK2;
    const double denominator = mTau + t;
    if (!(denominator > 0.0)) return mF;
    const double viscous = mK2 > 0.0 ? b * (1.0 + mK1 / mK2) * (x - mXPrev) : 0.0;
    mF = (mTau * mF + t * mK1 * x + viscous) / denominator;
    mXPrev = x;
    return mF;
}

PivotCorrection::PivotCorrection(const PivotParams& p) : mP(p) { reset(); }

void PivotCorrection::reset() noexcept
{
    const double h = mP.layerThicknessMm;
    for (auto& l : mLayers) l = KelvinElement(mP.kappa1NPerMm2 * h, mP.kappa2NPerMm2 * h, mP.tauS);
    mTouched = 0;
}

double PivotCorrection::update(double theta, double depthMm, double period) noexcept
{
    if (!std::isfinite(theta) || !std::isfinite(depthMm) || !(mP.hubDistanceMm > 0.0)) return 0.0;
    const double h = mP.layerThicknessMm;
    const int n = std::clamp(int(std::ceil(std::max(depthMm, 0.0) / h)), 0, kMaxLayers);
    mTouched = std::max(mTouched, n);
    double torque = 0.0;
    // Layers never reached have F = 0 and x = 0 and would stay so: only the touched ones step.
    for (int i = 0; i < mTouched; ++i) {
        const double r = (double(i) + 0.5) * h;   // depth of layer i below the pivot
        const double x = i < n ? r * theta : 0.0; // x_i ≈ r_i·θ; layers not reached relax to 0
        torque += mLayers[std::size_t(i)].step(x, period) * r;
    }
    const double f = torque / mP.hubDistanceMm;
    return std::clamp(f, -mP.maxForceN, mP.maxForceN);
}

} // namespace voxhap::haptic
