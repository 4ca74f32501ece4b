// SPDX-License-Identifier: Apache-2.0
/// @file VoxelLoops.h
/// @brief Parallel loops over every voxel of a lattice, for the segmentation sources.
#pragma once

#include "segmentation/lattice/Lattice.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>

namespace voxhap::segmentation::detail {

/// @brief f(n) for n in [0, count), in parallel chunks of 64 Ki voxels.
template <class F> void forEachVoxel(std::size_t count, F&& f)
{
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, count, 1 << 16), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) f(i);
        });
}

/// @brief The mask of the voxels n in [0, count) where pred(n).
template <class Pred> Mask maskWhere(std::size_t count, Pred&& pred)
{
    Mask m(count);
    forEachVoxel(count, [&](std::size_t i) { m[i] = pred(i) ? 1 : 0; });
    return m;
}

} // namespace voxhap::segmentation::detail
