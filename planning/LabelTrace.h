// SPDX-License-Identifier: Apache-2.0
/// @file LabelTrace.h
/// @brief haptic::traceLabelRuns for many lines: the same exact voxel traversal
/// (haptic/detail/Traversal.h), with the field's active box evaluated once
/// instead of per call. traceLabelRuns walks the grid trees for that box on every
/// call, which is most of the cost when a search traces thousands of short lines.
/// The same walk also collects the damping density β along the line, so the
/// force prediction needs no second traversal.
#pragma once

#include "haptic/LayerTables.h"
#include "haptic/MaterialField.h"

#include <memory>
#include <vector>

namespace voxhap::planning {

/// @brief β [N·s/mm²] constant over [startMm, endMm] of a traced line (voxel cells of the
/// piecewise-constant field, as the exact traversal reads it; zero pieces left out).
struct DampingPiece {
    double startMm = 0, endMm = 0, beta = 0;
};

class LabelTracer {
public:
    /// @throw ValueError if @p field has no label grid
    explicit LabelTracer(const haptic::MaterialField& field);
    ~LabelTracer();
    /// @brief As haptic::traceLabelRuns; with @p damping (and a damping grid in the
    /// field) also β along the line. Thread-safe (one reader per thread).
    /// @throw ValueError on a degenerate line
    std::vector<haptic::LabelRun> trace(const Vec3d& origin, const Vec3d& direction, double lengthMm,
                                        std::vector<DampingPiece>* damping = nullptr) const;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace voxhap::planning
