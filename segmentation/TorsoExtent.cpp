// SPDX-License-Identifier: Apache-2.0
/// @file TorsoExtent.cpp
/// @brief Cross-section widths of the body mask and the torso range.

#include "segmentation/TorsoExtent.h"

#include "segmentation/lattice/Components.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace voxhap::segmentation {

TorsoExtent torsoExtent(const volume::Volume& v, const Lattice& lat, const Mask& body)
{
    TorsoExtent e;
    const int slices = lat.dims[lat.sliceAxis];
    e.widthMm.assign(std::size_t(slices), 0.0);
    e.cut.assign(std::size_t(slices), 0);
    const ComponentRuns cc = componentRuns(lat, body, Span::Slice);
    if (cc.list.empty()) return e;

    // World x is affine in the lattice position: x = x0 + g · p.
    const volume::Geometry geo = v.geometry();
    const Vec3d g = (geo.direction.row(0).transpose().array() * geo.spacing.array()).matrix();
    const double x0 = geo.origin.x() + g.dot(lat.origin.cast<double>());
    const auto [a0, a1] = lat.planeAxes();
    // A voxel's own extent along x: its in-plane edges projected on x.
    const double voxelX = std::abs(g[a0]) + std::abs(g[a1]);
    // In-plane axes with a left-right component: touching their ends cuts the width.
    // [chosen] 0.3: an axis within 72° of LPS x; the other in-plane axis is then
    // the anterior-posterior one, whose ends do not shorten the width.
    constexpr double kLateralCosine = 0.3;
    const bool lateral0 = std::abs(geo.direction(0, a0)) > kLateralCosine;
    const bool lateral1 = std::abs(geo.direction(0, a1)) > kLateralCosine;
    const auto touches = [&](const Component& k, int a) { return k.min[a] == 0 || k.max[a] == lat.dims[a] - 1; };

    constexpr double inf = std::numeric_limits<double>::infinity();
    std::vector<double> lo(cc.list.size() + 1, inf), hi(cc.list.size() + 1, -inf);
    // x is monotone along a run (one index varies; rounding keeps the order), so
    // a run's extremes are at its ends.
    for (std::size_t r = 0; r < cc.runs.size(); ++r) {
        const auto c = std::size_t(cc.of[r]);
        const Run& run = cc.runs[r];
        const Vec3i row(0, run.row % lat.dims.y(), run.row / lat.dims.y());
        for (const int i : {run.begin, run.end - 1}) {
            const double x = x0 + g.dot(Vec3i(i, row.y(), row.z()).cast<double>());
            lo[c] = std::min(lo[c], x);
            hi[c] = std::max(hi[c], x);
        }
    }
    // The largest component of each slice gives the slice's width.
    std::vector<std::int64_t> largest(std::size_t(slices), 0);
    for (std::size_t c = 0; c < cc.list.size(); ++c) {
        const Component& k = cc.list[c];
        const auto s = std::size_t(k.min[lat.sliceAxis]);
        if (k.voxels <= largest[s]) continue;
        largest[s] = k.voxels;
        e.widthMm[s] = hi[c + 1] - lo[c + 1] + voxelX;
        e.cut[s] = (lateral0 && touches(k, a0)) || (lateral1 && touches(k, a1)) ? 1 : 0;
    }
    bool anyWhole = false;
    int bodyFirst = -1, bodyLast = -1;
    for (int s = 0; s < slices; ++s) {
        if (largest[std::size_t(s)] == 0) continue;
        ++e.bodySlices;
        anyWhole = anyWhole || !e.cut[std::size_t(s)];
        if (bodyFirst < 0) bodyFirst = s;
        bodyLast = s;
        if (e.widthMm[std::size_t(s)] >= kMinTorsoWidthMm) {
            if (e.first < 0) e.first = s;
            e.last = s;
        }
    }
    if (e.first < 0 && e.bodySlices > 0 && !anyWhole) {
        e.undetermined = true;
        e.first = bodyFirst;
        e.last = bodyLast;
    }
    for (int s = 0; s < slices; ++s) e.torsoSlices += largest[std::size_t(s)] > 0 && e.inTorso(s);
    return e;
}

double TorsoExtent::widestMm() const
{
    return widthMm.empty() ? 0.0 : *std::max_element(widthMm.begin(), widthMm.end());
}

double TorsoExtent::widestOutsideMm() const
{
    double w = 0.0;
    for (std::size_t s = 0; s < widthMm.size(); ++s) {
        if (!inTorso(int(s))) w = std::max(w, widthMm[s]);
    }
    return w;
}

double sliceZ(const volume::Volume& v, const Lattice& lat, int slice)
{
    Vec3d p = (lat.origin.cast<double>() + 0.5 * (lat.dims - Vec3i::Ones()).cast<double>());
    p[lat.sliceAxis] = lat.origin[lat.sliceAxis] + slice;
    return v.indexToWorld(p).z();
}

std::string torsoNote(const volume::Volume& v, const Lattice& lat, const TorsoExtent& e, const std::string& rules,
    const std::string& instead)
{
    if (e.bodySlices == 0) return {};
    char buf[512];
    if (e.undetermined) {
        std::snprintf(buf, sizeof buf,
            "%s applied without a check of the anatomy: the body is cut by the field of view left or right "
            "in every slice (at least %.0f mm across), so a torso (at least %.0f mm) cannot be told from a "
            "head or limb",
            rules.c_str(), e.widestMm(), kMinTorsoWidthMm);
        return buf;
    }
    if (e.all()) return {};
    if (e.none()) {
        std::snprintf(buf, sizeof buf,
            "%s not applied: the body is at most %.0f mm across (LPS x), narrower than an adult torso "
            "(at least %.0f mm): a head, neck or limb; %s",
            rules.c_str(), e.widestMm(), kMinTorsoWidthMm, instead.c_str());
    } else {
        const double z0 = sliceZ(v, lat, e.first), z1 = sliceZ(v, lat, e.last);
        std::snprintf(buf, sizeof buf,
            "%s applied only from z %.0f to %.0f mm, where the body is torso-wide (at least %.0f mm across); "
            "elsewhere it is at most %.0f mm across (a head, neck or limb): %s",
            rules.c_str(), std::min(z0, z1), std::max(z0, z1), kMinTorsoWidthMm, e.widestOutsideMm(), instead.c_str());
    }
    return buf;
}

} // namespace voxhap::segmentation
