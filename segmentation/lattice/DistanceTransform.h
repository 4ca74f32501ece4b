// SPDX-License-Identifier: Apache-2.0
/// @file DistanceTransform.h
/// @brief Exact Euclidean distance transform in millimetres on anisotropic voxels.
///
/// Felzenszwalb & Huttenlocher, "Distance Transforms of Sampled Functions",
/// Theory of Computing 8 (2012): the squared distance is separable, so one
/// pass of a 1-D lower envelope of parabolas per axis gives the exact result
/// in O(voxels) — each pass scaled by that axis's spacing, which is what makes
/// it exact on 1.07 × 1.07 × 3 mm voxels. Lines are independent: TBB runs them
/// in parallel.
#pragma once

#include "segmentation/lattice/Lattice.h"

#include <vector>

namespace voxhap::segmentation {

/// @brief Squared distance [mm²] from each voxel centre to the nearest centre
/// of a voxel where @p feature is set, along the axes of @p span (Slice: within
/// each slice only). Infinity where no feature is reachable. Voxels beyond the
/// lattice count as neither feature nor obstacle: they are not there.
/// @param complement measure to the voxels where @p feature is not set instead
std::vector<float> squaredDistance(const Lattice& lat, const Mask& feature, Span span, bool complement = false);

/// @brief The 1-D transform of one line, for callers that hold a slice or a slab
/// instead of the whole lattice: the same arithmetic as squaredDistance(), so
/// per-slice results equal the whole-lattice ones bit for bit.
class LineTransform {
public:
    /// @param n the longest line to be transformed
    explicit LineTransform(int n);
    /// @brief Replace the @p n values at data[q·step] (0 at features, +inf elsewhere,
    /// or the squared distances of earlier passes) by the lower envelope along the
    /// line, with voxel size @p h [mm]. A line without a finite value stays as it is.
    void apply(float* data, std::size_t step, int n, double h);

private:
    std::vector<double> mF, mD, mZ;
    std::vector<int> mV;
};

} // namespace voxhap::segmentation
