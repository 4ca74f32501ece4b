// SPDX-License-Identifier: Apache-2.0
/// @file LabelTrace.h
/// @brief Label runs along lines through a material field: the exact voxel
/// traversal (haptic/shaft/detail/Traversal.h), with the field's active box
/// evaluated once per tracer rather than per line, which is most of the cost
/// when a path search traces thousands of short lines (traceLabelRuns is the
/// one-line form).
/// The same walk also collects the damping density β along the line, so the
/// force prediction needs no second traversal.
#pragma once

#include "haptic/materials/MaterialField.h"

#include <memory>
#include <span>
#include <vector>

namespace voxhap::haptic {

/// @brief A run of one label along a line [mm from the line's origin].
struct LabelRun {
    int label = 0;
    double startMm = 0, endMm = 0;
};

/// @brief The label runs on the line origin + s·direction, s in [0, lengthMm], read
/// exactly from the field's label grid (voxel cells, openvdb::math::DDA). Leading
/// and trailing air are dropped; air inside stays a run.
/// @throw ValueError if the field has no label grid or the line is degenerate
std::vector<LabelRun> traceLabelRuns(
    const MaterialField& field, const Vec3d& origin, const Vec3d& direction, double lengthMm);

/// @brief β [N·s/mm²] constant over [startMm, endMm] of a traced line (voxel cells of the
/// piecewise-constant field, as the exact traversal reads it; zero pieces left out).
struct DampingPiece {
    double startMm = 0, endMm = 0, beta = 0;
};

class LabelTracer {
public:
    /// @throw ValueError if @p field has no label grid
    explicit LabelTracer(const MaterialField& field);
    ~LabelTracer();
    /// @brief As traceLabelRuns; with @p damping (and a damping grid in the
    /// field) also β along the line. Thread-safe (one reader per thread).
    /// @throw ValueError on a degenerate line
    std::vector<LabelRun> trace(const Vec3d& origin, const Vec3d& direction, double lengthMm,
        std::vector<DampingPiece>* damping = nullptr) const;
    /// @brief As trace(), along a bent path (physics.md §9.5): the polyline
    /// @p points, run bounds in mm along it from its first point.
    /// @throw ValueError on fewer than two points or a non-finite point
    std::vector<LabelRun> tracePolyline(
        std::span<const Vec3d> points, std::vector<DampingPiece>* damping = nullptr) const;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace voxhap::haptic
