// SPDX-License-Identifier: Apache-2.0
/// @file ContactTransient.cpp
/// @brief [S19] Eq. 2.

#include "haptic/force/ContactTransient.h"

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

double ContactTransient::forceN(double t, double impactMmPerS) const noexcept
{
    if (!(t > 0.0) || !(t <= durationS) || !std::isfinite(impactMmPerS)) return 0.0;
    constexpr double kTwoPi = 6.28318530717958647692;
    const double vIn = impactMmPerS * 1e-3; // m/s
    const double f =
        -amplitudeNsPerM * std::exp(std::log(0.01) * t / durationS) * std::sin(kTwoPi * frequencyHz * t) * vIn;
    return std::clamp(f, -peakClampN, peakClampN);
}

} // namespace voxhap::haptic
