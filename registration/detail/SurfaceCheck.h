// SPDX-License-Identifier: Apache-2.0
/// @file SurfaceCheck.h
/// @brief The registration's own plausibility check: do the two bodies' skins
/// meet? The CT's skin points that lie inside both fields of view, away from the
/// faces where a field of view cuts the body, are mapped into the MR and their
/// distance to the MR body's surface is read from a distance map (ITK's
/// Maurer transform). A body cut by both fields of view along one axis can only
/// be checked on its remaining faces.
#pragma once

#include "registration/AffineMap.h"
#include "registration/LevelImage.h"

#include <cstdint>

namespace voxhap::registration::detail {

struct SurfaceDistance {
    double meanMm = 0;       ///< mean distance over the points [mm]
    std::int64_t points = 0; ///< CT skin points checked
};

/// @brief Mean distance from the CT body's surface (mapped by @p mrFromCt) to
/// the MR body's surface, over the surface points inside both fields of view.
SurfaceDistance surfaceDistance(const LevelImage& ct, const LevelImage& mr, const AffineMap& mrFromCt);

/// @brief The fraction of the MR body whose voxels map (by the inverse of
/// @p mrFromCt) inside the CT's field of view.
double overlapFraction(const LevelImage& ct, const LevelImage& mr, const AffineMap& mrFromCt);

} // namespace voxhap::registration::detail
