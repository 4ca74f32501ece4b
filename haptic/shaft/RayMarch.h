// SPDX-License-Identifier: Apache-2.0
/// @file RayMarch.h
/// @brief The textbook baseline: fixed-step sampling along the shaft, trapezoid rule.
#pragma once

#include "haptic/shaft/ShaftIntegration.h"

namespace voxhap::haptic {

/// @brief March with steps of at most @p stepMm (the segment inside the active
/// box is cut into N = ceil(length/step) equal steps), sampling the nearest
/// voxel or the trilinear field, trapezoid rule. Error against the exact
/// integrals: physics.md §7 R1 gives the bound for the trilinear march.
std::unique_ptr<ShaftIntegrator> makeRayMarch(
    const MaterialField& field, double stepMm, bool trilinear, bool trackLabels);

} // namespace voxhap::haptic
