// SPDX-License-Identifier: Apache-2.0
/// @file DeviceLimits.cpp
/// @brief Device presets.

#include "haptic/DeviceLimits.h"

#include "core/Errors.h"

namespace voxhap::haptic {

DeviceLimits deviceLimits(std::string_view name)
{
    if (name == "touch") return DeviceLimits{}; // physics.md §6.3
    if (name == "phantom-premium") {
        // physics.md §1.1: 8.5 N peak [K01]. Continuous 1.4 N, stiffness 3.5 N/mm and
        // damping 0.005 N·s/mm are [chosen] for a Premium-class device (not in the sources).
        return DeviceLimits{"phantom-premium", 8.5, 1.4, 3.5, 0.005};
    }
    throw ValueError("unknown device '" + std::string(name) + "' (expected touch or phantom-premium)");
}

} // namespace voxhap::haptic
