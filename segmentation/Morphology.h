// SPDX-License-Identifier: Apache-2.0
/// @file Morphology.h
/// @brief Binary morphology with radii in millimetres (exact Euclidean balls
/// through DistanceTransform.h), per-slice hole filling, and smoothing.
#pragma once

#include "segmentation/Lattice.h"

#include <vector>

namespace voxhap::segmentation {

/// @brief Voxels of @p m farther than @p radiusMm from every voxel not in @p m.
/// Voxels beyond the lattice do not erode: a body cut by the scan's end keeps its ends.
Mask erode(const Lattice& lat, const Mask& m, double radiusMm, Span span);
/// @brief Voxels within @p radiusMm of a voxel of @p m.
Mask dilate(const Lattice& lat, const Mask& m, double radiusMm, Span span);
/// @brief Dilation then erosion: bridges gaps narrower than about 2·radius.
Mask close(const Lattice& lat, const Mask& m, double radiusMm, Span span);

/// @brief Set, in each slice, the voxels of @p m's complement that cannot be
/// reached from the slice's border through the complement (4-connected in-plane).
void fillHolesPerSlice(const Lattice& lat, Mask& m);

/// @brief Gaussian smoothing, separable, kernel truncated at 3σ, edges clamped.
/// Axes whose spacing exceeds 2σ are left alone (the kernel would be one tap).
std::vector<float> gaussianSmooth(const Lattice& lat, const std::vector<float>& values, double sigmaMm);

/// @brief Elementwise a AND b, a AND NOT b, a OR b.
Mask maskAnd(const Mask& a, const Mask& b);
Mask maskAndNot(const Mask& a, const Mask& b);
Mask maskOr(const Mask& a, const Mask& b);

} // namespace voxhap::segmentation
