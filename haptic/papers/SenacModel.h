// SPDX-License-Identifier: Apache-2.0
/// @file SenacModel.h
/// @brief Okamura/Sénac needle force terms (physics.md §2.1, §2.2): pre-puncture
/// stiffness a1·z + a2·z² and cutting by nested layer boxes.
#pragma once

#include <vector>

namespace voxhap::haptic {

/// @brief [S19] Eq. 4, F = a1·z + a2·z² along the elastic-plane normal, z >= 0.
struct PrePunctureStiffness {
    double a1NPerMm = 0;  ///< [N/mm]
    double a2NPerMm2 = 0; ///< [N/mm²]

    /// @brief §2.2 [chosen]: a1 = F_p/(2 z_p), a2 = F_p/(2 z_p²), so that both terms are
    /// equal at puncture and F(z_p) = F_p.
    static PrePunctureStiffness fromPuncture(double punctureForceN, double punctureDepthMm);
    double forceN(double zMm) const noexcept { return zMm > 0.0 ? zMm * (a1NPerMm + a2NPerMm2 * zMm) : 0.0; }
    /// @brief Slope dF/dz at z [N/mm], to compare with the device's stiffness limit.
    double slopeNPerMm(double zMm) const noexcept { return a1NPerMm + 2.0 * a2NPerMm2 * zMm; }
};

/// @brief [S19] Eq. 3 with nested boxes: the cutting force is the sum of the
/// forces of the layers the tip has entered (depth >= their start), applied only
/// while the speed exceeds ε (0.2 mm/s, §2.2 [chosen]).
struct NestedBoxCutting {
    struct Box {
        double startMm; ///< depth at which the tip enters the layer [mm]
        double forceN;  ///< F_layer [N]
    };
    std::vector<Box> boxes;
    double epsilonMmPerS = 0.2;

    /// @brief Magnitude of the cutting force [N]; it opposes the motion.
    double forceN(double depthMm, double speedMmPerS) const noexcept;
};

} // namespace voxhap::haptic
