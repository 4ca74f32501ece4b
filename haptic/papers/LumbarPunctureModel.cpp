// SPDX-License-Identifier: Apache-2.0
/// @file LumbarPunctureModel.cpp
/// @brief [LP] Eq. 1–3 (physics.md §4).

#include "haptic/papers/LumbarPunctureModel.h"

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

const std::vector<LpLayer>& lpTable()
{
    // physics.md §4, [LP] Table I, reproduced exactly.
    static const std::vector<LpLayer> kTable{
        {"out of skin", 5.0, 0.0, 0.0, 0.0},
        {"skin", 7.0, 330.0, 2.1, 0.3},
        {"fat", 14.0, 0.0, 1.0, 0.3},
        {"ligament", 30.0, 550.0, 3.0, 0.5},
        {"dura", 35.0, 980.0, 3.3, 0.6},
        {"puncture aim", 48.0, 0.0, 1.6, 0.2},
        {"bone", 55.0, 2370.0, 0.0, 0.0},
    };
    return kTable;
}

double lumbarPunctureForce(const std::vector<LpLayer>& layers, double depthMm, double velocityMmPerS, int lastDirection,
    const LpOptions& o) noexcept
{
    if (layers.empty() || !std::isfinite(depthMm) || !std::isfinite(velocityMmPerS)) return 0.0;
    if (velocityMmPerS <= 0.0) return o.keepDirectionN * (lastDirection < 0 ? -1.0 : 1.0); // Eq. 1, v <= 0
    const double v = velocityMmPerS * 1e-3;                                                // m/s
    double start = 0.0, viscous = 0.0, tip = 0.0, coulomb = 0.0;
    for (const LpLayer& l : layers) {
        const double inLayer = std::clamp(depthMm - start, 0.0, l.endMm - start); // [mm]
        viscous += l.bNsPerM2 * v * inLayer * 1e-3;                               // b·v·l [N]
        if (depthMm >= start && (depthMm < l.endMm || &l == &layers.back())) {
            tip = l.kNPerM * (depthMm - start) * 1e-3; // k·x, x into the tip's layer [chosen]
            coulomb = l.cN;
        }
        start = l.endMm;
    }
    const double friction = velocityMmPerS < o.deltaVMmPerS ? viscous : coulomb + viscous; // Eq. 3
    return -(tip + friction);
}

} // namespace voxhap::haptic
