// SPDX-License-Identifier: Apache-2.0
/// @file Components.h
/// @brief Connected components of a mask, their sizes and boxes, and region
/// growing from labelled seeds.
#pragma once

#include "segmentation/Lattice.h"

#include <cstdint>
#include <vector>

namespace voxhap::segmentation {

/// @brief One connected component.
struct Component {
    std::int64_t voxels = 0;
    Vec3i min{0, 0, 0}, max{0, 0, 0}; ///< lattice bounding box, inclusive
};

/// @brief Component ids per voxel (0: not in the mask, else 1..n) and the components.
struct Components {
    std::vector<std::int32_t> id;
    std::vector<Component> list; ///< list[c - 1] is component c
};

/// @brief Face-connected components of @p m: 6-connected for Span::Volume,
/// 4-connected within each slice for Span::Slice.
Components connectedComponents(const Lattice& lat, const Mask& m, Span span);

/// @brief The mask of the largest component (empty mask if @p m is empty).
Mask largestComponent(const Lattice& lat, const Mask& m);

/// @brief Grow the labelled seeds in @p ids (0 = unlabelled) through the voxels
/// of @p within, breadth first and face-connected: each voxel takes the label of
/// the seed that reaches it first, i.e. the nearest in 6-connected steps.
void growRegions(const Lattice& lat, std::vector<std::int32_t>& ids, const Mask& within);

} // namespace voxhap::segmentation
