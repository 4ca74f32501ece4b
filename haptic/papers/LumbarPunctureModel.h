// SPDX-License-Identifier: Apache-2.0
/// @file LumbarPunctureModel.h
/// @brief The lumbar-puncture force model with Karnopp friction, [LP] Eq. 1–3
/// (physics.md §4), and the paper's Table I reproduced exactly.
///
///   f = f_tip + f_friction + f_mechanic   (v > 0);   f = f_keepdir   (v <= 0)
///   f_tip = -k·x                           x: depth into the layer at the tip [chosen]
///   f_friction = -b·v·l  (v < Δv);  -C - b·v·l  (v >= Δv)
/// with b·v·l summed over the layers on the shaft and C of the layer at the tip
/// [chosen]. f_mechanic compensates the paper's device friction: 0 here.
#pragma once

#include <string>
#include <vector>

namespace voxhap::haptic {

/// @brief One row of [LP] Table I, in the paper's units.
struct LpLayer {
    std::string name;
    double endMm = 0;    ///< end of layer, depth from the start of the table [mm]
    double kNPerM = 0;   ///< elasticity k [N/m]
    double bNsPerM2 = 0; ///< viscosity coefficient b [N·s/m²]
    double cN = 0;       ///< Coulomb friction C [N]
};

/// @brief [LP] Table I exactly: out of skin 5, skin 7, fat 14, ligament 30, dura 35,
/// puncture aim 48, bone 55 mm.
const std::vector<LpLayer>& lpTable();

/// @brief Options of the model.
struct LpOptions {
    /// Karnopp threshold Δv [mm/s]: the paper's 0.01 m/s. physics.md §4 suggests about
    /// 1 mm/s [chosen] so that expert speeds (1–3 mm/s, [S19]) keep the Coulomb term.
    double deltaVMmPerS = 10.0;
    double keepDirectionN = 0.001; ///< f_keepdir [N] ([LP]: stops the belt drive chattering)
};

/// @brief Axial force [N] at depth @p depthMm (from the table's start) moving at
/// @p velocityMmPerS along the insertion axis; positive pushes inward. For v <= 0
/// it is f_keepdir in the last motion direction (@p lastDirection, +1 or -1).
double lumbarPunctureForce(const std::vector<LpLayer>& layers, double depthMm, double velocityMmPerS, int lastDirection,
    const LpOptions& options = {}) noexcept;

} // namespace voxhap::haptic
