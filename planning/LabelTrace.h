// SPDX-License-Identifier: Apache-2.0
/// @file LabelTrace.h
/// @brief haptic::traceLabelRuns for many lines: the same exact voxel traversal
/// (haptic/detail/Traversal.h), with the field's active box evaluated once
/// instead of per call. traceLabelRuns walks the grid trees for that box on every
/// call, which is most of the cost when a search traces thousands of short lines.
#pragma once

#include "haptic/LayerTables.h"
#include "haptic/MaterialField.h"

#include <memory>
#include <vector>

namespace voxhap::planning {

class LabelTracer {
public:
    /// @throw ValueError if @p field has no label grid
    explicit LabelTracer(const haptic::MaterialField& field);
    ~LabelTracer();
    /// @brief As haptic::traceLabelRuns. Thread-safe (one reader per thread).
    /// @throw ValueError on a degenerate line
    std::vector<haptic::LabelRun> trace(const Vec3d& origin, const Vec3d& direction, double lengthMm) const;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace voxhap::planning
