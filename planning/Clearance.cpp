// SPDX-License-Identifier: Apache-2.0
/// @file Clearance.cpp
#include "planning/Clearance.h"

#include "volume/Grids.h"

#include <openvdb/tools/Interpolation.h>

#include <algorithm>
#include <cmath>

namespace voxhap::planning {

namespace {
/// Lipschitz bound of a trilinearly interpolated unit-slope distance field (see the header).
constexpr double kLipschitz = 1.7320508075688772;
} // namespace

Clearance clearanceAlong(
    const volume::Volume::GridConstPtr& field, const Vec3d& a, const Vec3d& b, double toleranceMm, double bandMm)
{
    const auto grid = openvdb::gridConstPtrCast<volume::FloatGrid>(field);
    Clearance c;
    if (!grid) return c;
    auto acc = grid->getConstAccessor();
    const openvdb::tools::GridSampler<volume::FloatGrid::ConstAccessor, openvdb::tools::BoxSampler> sampler(
        acc, grid->transform());
    const double len = (b - a).norm();
    const Vec3d u = len > 0 ? Vec3d((b - a) / len) : Vec3d(0, 0, 1);
    const double h = std::max(toleranceMm, 1e-3);
    double best = std::numeric_limits<double>::infinity(), at = 0.0;
    for (double s = 0.0;;) {
        const Vec3d p = a + s * u;
        const double phi = sampler.wsSample(volume::toVdb(p));
        if (phi < best) best = phi, at = s;
        if (s >= len) break;
        const double eps = std::max(h, 0.1 * std::min(best, bandMm)); // the header's tolerance
        s = std::min(len, s + (phi - best + eps) / kLipschitz);
    }
    c.minMm = best;
    c.atDepthMm = at;
    // Beyond the band the field holds its background: the true clearance is at least that.
    c.beyondBand = best >= bandMm - 1e-6;
    return c;
}

} // namespace voxhap::planning
