// SPDX-License-Identifier: Apache-2.0
/// @file Components.h
/// @brief Connected components of a mask, their sizes and boxes, and region
/// growing from labelled seeds.
///
/// Components are found on runs (maximal stretches of set voxels along the
/// lattice's fastest axis), not on voxels: a body mask of 35 M voxels has about
/// 10⁵ runs, so the union-find and the per-component figures cost next to
/// nothing, and callers that only need a mask of some components never hold a
/// dense array of ids (ComponentRuns). Numbering is by each component's first
/// voxel in memory order, as a serial flood fill in that order would give.
#pragma once

#include "segmentation/lattice/Lattice.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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

/// @brief A stretch of set voxels along lattice axis 0: elements
/// [row·dims.x + begin, row·dims.x + end) with row = j + dims.y·k.
struct Run {
    std::int32_t row = 0, begin = 0, end = 0;
};

/// @brief Components as runs: no per-voxel array.
struct ComponentRuns {
    std::vector<Run> runs;             ///< in memory order
    std::vector<std::int32_t> of;      ///< component (1..n) of each run
    std::vector<std::size_t> rowStart; ///< runs of row r: [rowStart[r], rowStart[r + 1])
    std::vector<Component> list;       ///< list[c - 1] is component c

    /// @brief The mask of the voxels whose component c has keep[c] != 0 (keep[0] unused).
    Mask mask(const Lattice& lat, const std::vector<std::uint8_t>& keep) const;
    /// @brief Calls f(component, first element, end element) for every run, rows in parallel.
    template <class F> void forEachRun(const Lattice& lat, F&& f) const;
};

/// @brief Face-connected components of @p m as runs: 6-connected for
/// Span::Volume, 4-connected within each slice for Span::Slice. Rows are
/// labelled in parallel slabs, then joined across the slabs' borders.
ComponentRuns componentRuns(const Lattice& lat, const Mask& m, Span span);

/// @brief Face-connected components of @p m with an id per voxel (componentRuns, painted).
Components connectedComponents(const Lattice& lat, const Mask& m, Span span);

/// @brief The mask of the largest component (empty mask if @p m is empty); of
/// equal sizes, the first in memory order.
Mask largestComponent(const Lattice& lat, const Mask& m);

/// @brief Grow the labelled seeds in @p ids (0 = unlabelled) through the voxels
/// of @p within, breadth first and face-connected: each voxel takes the label of
/// the seed that reaches it first, i.e. the nearest in 6-connected steps; of
/// fronts arriving in the same step, the first in the front's order (the seeds
/// in memory order, then their discoveries in order) wins. Each step runs in
/// parallel and gives what the serial breadth-first pass gives, voxel for voxel.
void growRegions(const Lattice& lat, std::vector<std::int32_t>& ids, const Mask& within);

template <class F> void ComponentRuns::forEachRun(const Lattice& lat, F&& f) const
{
    const auto rows = std::int64_t(rowStart.size()) - 1;
    const auto nx = std::size_t(lat.dims.x());
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, rows, 256), [&](const tbb::blocked_range<std::int64_t>& r) {
        for (std::int64_t row = r.begin(); row != r.end(); ++row) {
            for (std::size_t n = rowStart[std::size_t(row)]; n != rowStart[std::size_t(row) + 1]; ++n) {
                const std::size_t base = std::size_t(row) * nx;
                f(of[n], base + std::size_t(runs[n].begin), base + std::size_t(runs[n].end));
            }
        }
    });
}

} // namespace voxhap::segmentation
