// SPDX-License-Identifier: Apache-2.0
/// @file Morphology.h
/// @brief Binary morphology with radii in millimetres (exact Euclidean balls
/// through DistanceTransform.h), per-slice hole filling, and smoothing.
///
/// None of these holds a distance array over the whole lattice: per-slice
/// operations work one slice at a time, and the 3-D ones in slabs of k planes
/// with only the planes within the radius around them (a voxel farther away
/// along k cannot decide a threshold at the radius). The results equal those
/// of thresholding squaredDistance() over the whole lattice.
#pragma once

#include "segmentation/lattice/Lattice.h"

#include <functional>
#include <vector>

namespace voxhap::segmentation {

/// @brief Voxels of @p m farther than @p radiusMm from every voxel not in @p m.
/// Voxels beyond the lattice do not erode: a body cut by the scan's end keeps its ends.
Mask erode(const Lattice& lat, const Mask& m, double radiusMm, Span span);
/// @brief Voxels within @p radiusMm of a voxel of @p m.
Mask dilate(const Lattice& lat, const Mask& m, double radiusMm, Span span);
/// @brief Dilation then erosion: bridges gaps narrower than about 2·radius.
Mask close(const Lattice& lat, const Mask& m, double radiusMm, Span span);

/// @brief Voxels of @p m nearer than @p radiusMm, in their slice, to a voxel not in @p m.
Mask innerShell(const Lattice& lat, const Mask& m, double radiusMm);

/// @brief Set, in each slice, the voxels of @p m's complement that cannot be
/// reached from the slice's border through the complement (4-connected in-plane).
void fillHolesPerSlice(const Lattice& lat, Mask& m);

/// @brief Gaussian smoothing, separable, kernel truncated at 3σ, edges clamped.
/// Axes whose spacing exceeds 2σ are left alone (the kernel would be one tap).
std::vector<float> gaussianSmooth(const Lattice& lat, const std::vector<float>& values, double sigmaMm);

/// @brief gaussianSmooth() without the lattice-sized arrays: @p read fills k planes
/// [k0, k1) of the input (i fastest, then j, then k) into its buffer, and @p sink
/// receives each smoothed k plane (dims.x · dims.y values), from parallel tasks.
/// The values are those of gaussianSmooth(), bit for bit.
void gaussianSmoothPlanes(const Lattice& lat, double sigmaMm,
    const std::function<void(int k0, int k1, float* out)>& read,
    const std::function<void(int k, const float* plane)>& sink);

/// @brief Elementwise a AND b, a AND NOT b, a OR b.
Mask maskAnd(const Mask& a, const Mask& b);
Mask maskAndNot(const Mask& a, const Mask& b);
Mask maskOr(const Mask& a, const Mask& b);

} // namespace voxhap::segmentation
