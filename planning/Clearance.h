// SPDX-License-Identifier: Apache-2.0
/// @file Clearance.h
/// @brief The smallest signed distance to a structure along a segment, from the
/// structure's distance field (segmentation/DistanceField.h).
#pragma once

#include "planning/Trajectory.h"
#include "volume/Volume.h"

namespace voxhap::planning {

/// @brief min over s in [0, |b − a|] of the trilinear field at a + s·û, to within
/// max(@p toleranceMm, c/10) for a clearance c: a structure 25 mm away is known to
/// 2.5 mm, which no planning decision needs better, and it keeps the march short.
///
/// Sphere tracing: a distance field changes by at most its Lipschitz constant
/// per mm, so from a sample of value φ, with m the smallest value so far and ε
/// the tolerance, nothing within (φ − m + ε)/L can go below m − ε and the march
/// skips it. For the exact
/// Euclidean distance L = 1; the trilinear interpolant of its samples changes by
/// at most one voxel's worth per voxel along each axis, hence L ≤ √3. Far from
/// every structure (the band's background) the steps are long, which is what makes
/// the candidate search fast; near one they shrink to @p toleranceMm.
/// @param field a FloatGrid sharing its transform with the volume
/// @param bandMm the field's background: a minimum at or beyond it is reported beyondBand
Clearance clearanceAlong(
    const volume::Volume::GridConstPtr& field, const Vec3d& a, const Vec3d& b, double toleranceMm, double bandMm);

} // namespace voxhap::planning
