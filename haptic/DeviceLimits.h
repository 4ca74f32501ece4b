// SPDX-License-Identifier: Apache-2.0
/// @file DeviceLimits.h
/// @brief What a haptic device can render, as data (style.md §2, after CHAI3D's
/// cHapticDeviceInfo): forces are clamped and stiffnesses limited against it.
#pragma once

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
};

/// @brief Named presets: "touch" (Touch/Omni class: 3.3 N peak, 0.88 N continuous,
/// 0.5 N/mm, from public OpenHaptics sample output, physics.md §6.3) and
/// "phantom-premium" ([K01] PHANToM, 8.5 N peak, §1.1; its continuous force,
/// stiffness and damping are [chosen]). @throw ValueError on an unknown name
DeviceLimits deviceLimits(std::string_view name);

} // namespace voxhap::haptic
