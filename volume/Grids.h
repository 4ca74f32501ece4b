// SPDX-License-Identifier: Apache-2.0
/// @file Grids.h
/// @brief Typed access to a Volume's OpenVDB grids, and Eigen <-> OpenVDB conversions.
///
/// This is the one header that brings in <openvdb/openvdb.h> (15-20 s of
/// compile time per translation unit): include it from .cpp files, and from
/// the internal headers those share (haptic/materials/FieldGrids.h,
/// haptic/shaft/detail/, segmentation/lattice/DenseGrids.h), never from a header of a
/// library's API.
#pragma once

#include "volume/Volume.h"

#include <openvdb/openvdb.h>

namespace voxhap::volume {

using FloatGrid = openvdb::FloatGrid; ///< hu, t1 and derived material grids
using LabelGrid = openvdb::Int32Grid; ///< tissue ids

/// @brief Initialise OpenVDB's grid registry once (thread-safe, idempotent).
void initializeOpenVdb();

/// @brief The `hu` grid, or nullptr if absent.
FloatGrid::ConstPtr huGrid(const Volume& v);
/// @brief The `t1` grid, or nullptr if absent.
FloatGrid::ConstPtr t1Grid(const Volume& v);
/// @brief The `intensity` grid (MR that is not T1), or nullptr if absent.
FloatGrid::ConstPtr intensityGrid(const Volume& v);
/// @brief The `label` grid, or nullptr if absent.
LabelGrid::ConstPtr labelGrid(const Volume& v);

inline openvdb::Vec3d toVdb(const Vec3d& v) { return {v.x(), v.y(), v.z()}; }
inline Vec3d fromVdb(const openvdb::Vec3d& v) { return {v.x(), v.y(), v.z()}; }
inline openvdb::Coord toCoord(const Vec3i& v) { return openvdb::Coord(v.x(), v.y(), v.z()); }
inline Vec3i fromCoord(const openvdb::Coord& c) { return {c.x(), c.y(), c.z()}; }
inline openvdb::CoordBBox toCoordBBox(const IndexBox& b) { return {toCoord(b.min), toCoord(b.max)}; }

} // namespace voxhap::volume
