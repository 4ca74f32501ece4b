// SPDX-License-Identifier: Apache-2.0
/// @file Rasterize.h
/// @brief Turn an analytic tissue classifier (world point -> tissue id) into
/// a Volume with consistent hu, t1 and label grids, and trace the layers a
/// straight path crosses in the analytic model.
#pragma once

#include "core/Math.h"
#include "volume/TissueTable.h"
#include "volume/Volume.h"

#include <functional>
#include <string>
#include <vector>

namespace voxhap::volume {

/// @brief Tissue id at a world point [mm, LPS]; 0 is air.
/// @warning Called concurrently from several threads: must be a pure function.
using Classifier = std::function<int(const Vec3d& world)>;

/// @brief Sampling lattice of a synthetic volume.
struct GridSpec {
    Vec3d spacing{0.5, 0.5, 0.5};              ///< voxel size along i, j, k [mm]; anisotropic allowed
    Mat3d direction = Mat3d::Identity();       ///< rotation: columns are the world directions of i, j, k
    FieldStrength field = FieldStrength::T1_5; ///< which T1 column fills the t1 grid
};

/// @brief An axis-aligned world box [mm].
struct WorldBox {
    Vec3d min;
    Vec3d max;
};

/// @brief Sample @p classify at the centres of the voxels that cover @p bounds
/// and fill hu (typical HU), t1 (T1 at the spec's field) and label from @p table.
///
/// The lattice is anchored at the world origin: voxel faces lie on the planes
/// world = direction·diag(spacing)·n for integer n, so layer boundaries placed
/// at multiples of the spacing fall exactly on faces (physics.md §7 R1).
/// Air (id 0) stays inactive in all three grids; uniform regions become tiles.
/// Runs in parallel (TBB).
/// @throw ValueError if the classifier returns an id the table does not hold.
Volume rasterize(const Classifier& classify, const WorldBox& bounds, const GridSpec& spec, const TissueTable& table);

/// @brief The tissue intervals (LayerSpan, VolumeMetadata.h) along entry + s·direction, s in [0, length],
/// of the analytic classifier (not the voxels): boundaries located by bisection
/// to 1e-9 mm after a scan at @p stepMm (features thinner than the step may be missed).
std::vector<LayerSpan> traceLayers(const Classifier& classify, const Vec3d& entry, const Vec3d& direction,
    double length, const TissueTable& table, double stepMm = 0.05);

} // namespace voxhap::volume
