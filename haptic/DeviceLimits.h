// SPDX-License-Identifier: Apache-2.0
/// @file DeviceLimits.h
/// @brief What a haptic device can render, as data (style.md §2, after CHAI3D's
/// cHapticDeviceInfo): forces are clamped and stiffnesses limited against it.
#pragma once

#include <array>
#include <string>
#include <string_view>

namespace voxhap::haptic {

/// @brief Rendering limits of a haptic device (physics.md §6.3).
struct DeviceLimits {
    std::string name = "touch";
    double maxForceN = 3.3;            ///< peak force [N]
    double maxContinuousForceN = 0.88; ///< sustained force [N]
    double maxStiffnessNPerMm = 0.5;   ///< highest stable virtual stiffness [N/mm]
    double maxDampingNsPerMm = 0.002;  ///< highest stable virtual damping [N·s/mm] [chosen]
    /// Mass of the handle (and needle) the device must hold up [kg]: Kyung's gravity
    /// compensation F_G = −m·g of Eq. 1 (physics.md §1.1). 0 for a device that
    /// compensates its own weight in firmware or by counterweights.
    double handleMassKg = 0.0;
    /// The direction of gravity in world axes (LPS), unit length. Default anterior
    /// (−y): the patient lies prone, as for a spine biopsy or a lumbar puncture from
    /// the back, and the needle goes in downward [chosen].
    std::array<double, 3> down{0.0, -1.0, 0.0};
};

/// Standard gravity g_n [m/s²] (CGPM 1901, ISO 80000-3): Kyung's F_G = −m·g (physics.md §1.1).
inline constexpr double kStandardGravityMPerS2 = 9.80665;

/// @brief Named presets: "touch" (Touch/Omni class: 3.3 N peak, 0.88 N continuous,
/// 0.5 N/mm, from public OpenHaptics sample output, physics.md §6.3) and
/// "phantom-premium" ([K01] PHANToM, 8.5 N peak, §1.1; its continuous force,
/// stiffness and damping are [chosen]). @throw ValueError on an unknown name
DeviceLimits deviceLimits(std::string_view name);

} // namespace voxhap::haptic
