// SPDX-License-Identifier: Apache-2.0
/// @file Resample.h
/// @brief An MR channel carried onto a CT's grid through a registration's
/// `mr_from_ct` map: trilinear values at the CT's voxel centres, active where
/// the MR's body is (the nearest MR voxel is active) and inside the CT's box.
/// Sparse throughout: only the MR body's neighbourhood is visited.
#pragma once

#include "registration/AffineMap.h"
#include "volume/Volume.h"

#include <cstdint>

namespace voxhap::registration {

struct ResampleReport {
    std::int64_t activeVoxels = 0; ///< CT-grid voxels that received an MR value
    double seconds = 0;
};

/// @brief Channel @p c of @p mr on @p ct's grid (a FloatGrid with @p ct's
/// transform and the channel's air background).
/// @throw ValueError if @p mr lacks the channel or it is not a float channel
volume::Volume::GridPtr resampleOnto(const volume::Volume& ct, const volume::Volume& mr, volume::Channel c,
    const AffineMap& mrFromCt, ResampleReport* report = nullptr);

} // namespace voxhap::registration
