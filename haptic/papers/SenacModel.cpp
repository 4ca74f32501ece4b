// SPDX-License-Identifier: Apache-2.0
/// @file SenacModel.cpp
/// @brief [S19] Eq. 3 and 4 (physics.md §2).

#include "haptic/papers/SenacModel.h"

#include "core/Errors.h"

#include <cmath>

namespace voxhap::haptic {

PrePunctureStiffness PrePunctureStiffness::fromPuncture(double fp, double zp)
{
    if (!(fp >= 0.0) || !(zp > 0.0) || !std::isfinite(fp) || !std::isfinite(zp)) {
        throw ValueError("pre-puncture stiffness: puncture force must be >= 0 and depth > 0");
    }
    return {fp / (2.0 * zp), fp / (2.0 * zp * zp)};
}

double NestedBoxCutting::forceN(double depthMm, double speedMmPerS) const noexcept
{
    if (!(std::abs(speedMmPerS) > epsilonMmPerS) || !std::isfinite(depthMm)) return 0.0; // §2.1: only when ‖v‖ > ε
    double sum = 0.0;
    for (const Box& b : boxes) {
        if (depthMm >= b.startMm) sum += b.forceN;
    }
    return sum;
}

} // namespace voxhap::haptic
