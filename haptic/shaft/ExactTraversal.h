// SPDX-License-Identifier: Apache-2.0
/// @file ExactTraversal.h
/// @brief Factories of the exact strategies (see ShaftIntegration.h).
#pragma once

#include "haptic/shaft/ShaftIntegration.h"

namespace voxhap::haptic {

/// @brief Voxel by voxel (openvdb::math::DDA), each voxel's β weighted by its
/// exact chord in mm: exact for the piecewise-constant field, on any spacing.
std::unique_ptr<ShaftIntegrator> makeExactVoxel(const MaterialField& field, bool trackLabels);

/// @brief Cell by cell between voxel centres, the trilinear field's cubic along
/// the chord integrated exactly (two-point Gauss–Legendre is exact for cubics).
std::unique_ptr<ShaftIntegrator> makeExactTrilinear(const MaterialField& field, bool trackLabels);

} // namespace voxhap::haptic
