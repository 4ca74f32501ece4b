// SPDX-License-Identifier: Apache-2.0
/// @file DistanceField.h
/// @brief Signed distance fields of critical structures, for clearance queries in mm.
///
/// Why not OpenVDB's level-set tools: they assume cubic voxels (one voxel
/// size), and patient volumes have 3 mm slices under 1 mm pixels. The field
/// here is the exact Euclidean distance transform in millimetres
/// (DistanceTransform.h) between voxel centres, shifted by half a voxel
/// because the surface lies between the last voxel centre inside and the
/// first outside: the result is within half a voxel of the distance to the
/// true surface along a grid axis.
#pragma once

#include "segmentation/lattice/Lattice.h"
#include "volume/Volume.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::segmentation {

/// @brief Derived-grid name of a tissue's distance field: "sdf.<tissue>".
std::string distanceFieldName(const std::string& tissue);

/// @brief Signed distance [mm] to the surface of the voxels where @p labels == @p id:
/// negative inside, positive outside; voxels farther out than @p bandMm are inactive
/// and read as the background +@p bandMm; inside values are clamped at −@p bandMm.
/// @return a FloatGrid (volume/Grids.h), handed out as a base pointer so that
///         this header does not bring OpenVDB's into every includer
/// The field is computed over the structure's box widened by the band and a voxel
/// (clamped to @p bounds, default @p lat): beyond it every value is the background,
/// and the widened box's outer layer is outside the structure, so its distances
/// are those of the whole lattice.
/// @param bounds the lattice the field may cover; @p lat must lie within it
/// @brief The box signedDistanceField() computes over: the voxels where @p labels == @p id,
/// widened by the band and a voxel, clamped to @p bounds (default @p lat); empty
/// dims if there is no such voxel.
Lattice distanceFieldBox(const Lattice& lat, const std::vector<std::int32_t>& labels, std::int32_t id, double bandMm,
    const std::optional<Lattice>& bounds = std::nullopt);

volume::Volume::GridPtr signedDistanceField(const Lattice& lat, const std::vector<std::int32_t>& labels,
    std::int32_t id, double bandMm, const std::optional<Lattice>& bounds = std::nullopt);

} // namespace voxhap::segmentation
