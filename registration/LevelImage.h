// SPDX-License-Identifier: Apache-2.0
/// @file LevelImage.h
/// @brief The images a registration compares: one channel of a Volume,
/// block-averaged to a coarser lattice of the same orientation, with the body
/// mask that keeps air out of the metric (docs/reference.md "CT and MR fusion").
///
/// The sparse grids hold the body as active voxels and air as the inactive
/// background; a block of f_i × f_j × f_k voxels becomes one voxel whose value
/// is the mean over the block (air counted at the background value) and which
/// belongs to the body when at least half the block is active. Block averaging
/// is the anti-aliasing of the pyramid: a level never samples finer detail
/// than its own voxels hold.
#pragma once

#include "volume/Volume.h"

#include <cstdint>
#include <vector>

namespace voxhap::registration {

/// @brief A dense image of one channel on a block lattice of a volume's grid.
struct LevelImage {
    volume::Geometry geometry;      ///< voxel centres: world = origin + direction·diag(spacing)·ijk
    Vec3i dims{0, 0, 0};            ///< voxels along i, j, k
    std::vector<float> values;      ///< i fastest, then j, then k
    std::vector<std::uint8_t> body; ///< 1 where the block is at least half active (the body)

    std::int64_t count() const { return std::int64_t(dims.x()) * dims.y() * dims.z(); }
    std::int64_t index(int i, int j, int k) const { return (std::int64_t(k) * dims.y() + j) * dims.x() + i; }
    Vec3d world(const Vec3d& ijk) const
    {
        return geometry.origin + geometry.direction * geometry.spacing.cwiseProduct(ijk);
    }
    Vec3d toIndex(const Vec3d& world) const
    {
        return (geometry.direction.transpose() * (world - geometry.origin)).cwiseQuotient(geometry.spacing);
    }
    /// @brief The world box of the voxel faces along the image's own axes is
    /// the field of view; true if @p world lies inside it.
    bool inside(const Vec3d& world) const;
    /// @brief Number of body voxels.
    std::int64_t bodyCount() const;
    /// @brief Mean world position of the body voxels [mm].
    Vec3d bodyCentroid() const;
};

/// @brief The air value of an image channel (hu −1000, t1 and intensity 0).
/// @throw ValueError for the label channel
float backgroundOf(volume::Channel c);

/// @brief Block factors that bring each spacing near @p targetMm (at least 1).
Vec3i blockFactors(const Vec3d& spacing, double targetMm);

/// @brief Block-average channel @p c of @p v by @p factors over its index box
/// (a partial block at the far edge is dropped). Parallel over the grid's leaves.
/// @throw ValueError if the volume lacks the channel or the box is smaller than a block
LevelImage blockAverage(const volume::Volume& v, volume::Channel c, const Vec3i& factors);

/// @brief Block-average a level image again by @p factors (the next pyramid level).
LevelImage blockAverage(const LevelImage& fine, const Vec3i& factors);

/// @brief Make the body the voxels above @p threshold that form the largest
/// 6-connected component once opened by @p openingVoxels (what joins it through
/// parts thinner than twice that is cut off), with its holes filled (whatever the image's border
/// cannot reach through the rest): a CT's patient without the table and the
/// positioning aids the loader kept, and without inner surfaces (gas, marrow)
/// that are no skin.
void bodyAbove(LevelImage& image, float threshold, int openingVoxels = 0);

/// @brief The body grown by @p passes face-neighbour steps into the air.
std::vector<std::uint8_t> grownBody(const LevelImage& image, int passes);

/// @brief Clamp every value to [lo, hi] (a display window for the metric's histogram).
void clampValues(LevelImage& image, float lo, float hi);

/// @brief The value below which @p fraction of the body's values lie (0 for an empty body).
float bodyQuantile(const LevelImage& image, double fraction);

/// @brief bodyQuantile at each of @p fractions, from one gathering of the values.
std::vector<float> bodyQuantiles(const LevelImage& image, const std::vector<double>& fractions);

} // namespace voxhap::registration
