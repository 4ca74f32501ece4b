// SPDX-License-Identifier: Apache-2.0
/// @file BodyWidth.cpp
/// @brief Per-section LPS x extents of a grid's active voxels.

#include "volume/mr/BodyWidth.h"

#include "core/Errors.h"
#include "volume/Grids.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace voxhap::volume {

BodyWidth measureBodyWidth(const Volume& v, const openvdb::GridBase& base)
{
    // Section thickness [chosen]: 2 mm, finer than any slice step that matters
    // for a width and coarse enough that a section holds whole voxels' worth.
    constexpr double kSectionMm = 2.0;
    struct Section {
        double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
        bool cut = false;
    };
    std::map<long, Section> sections;
    const Geometry g = v.geometry();
    Vec3d axis[3];
    bool leftRight[3];
    for (int a = 0; a < 3; ++a) {
        axis[a] = g.direction.col(a) * g.spacing[a];
        leftRight[a] = std::abs(g.direction(0, a)) >= std::sqrt(0.5);
    }
    // Half a voxel's reach along x, so that widths count voxel faces.
    double halfX = 0;
    for (int a = 0; a < 3; ++a) halfX += 0.5 * std::abs(axis[a].x());
    const IndexBox& box = v.indexBox();
    const auto add = [&](const openvdb::Coord& c) {
        const Vec3d w = g.origin + axis[0] * c.x() + axis[1] * c.y() + axis[2] * c.z();
        Section& s = sections[long(std::floor(w.z() / kSectionMm))];
        s.lo = std::min(s.lo, w.x() - halfX);
        s.hi = std::max(s.hi, w.x() + halfX);
        for (int a = 0; a < 3; ++a) {
            if (leftRight[a] && (c[a] <= box.min[a] || c[a] >= box.max[a])) s.cut = true;
        }
    };
    if (const auto* f = dynamic_cast<const FloatGrid*>(&base)) {
        for (auto it = f->cbeginValueOn(); it; ++it) {
            openvdb::CoordBBox bb;
            it.getBoundingBox(bb);
            for (auto c = bb.begin(); c; ++c) add(*c);
        }
    } else if (const auto* l = dynamic_cast<const LabelGrid*>(&base)) {
        for (auto it = l->cbeginValueOn(); it; ++it) {
            openvdb::CoordBBox bb;
            it.getBoundingBox(bb);
            for (auto c = bb.begin(); c; ++c) add(*c);
        }
    } else {
        throw ValueError("measureBodyWidth: not a float or label grid");
    }
    BodyWidth out;
    for (const auto& [z, s] : sections) {
        ++out.sections;
        const double width = s.hi - s.lo;
        if (s.cut) {
            ++out.cutSections;
            out.widestCutMm = std::max(out.widestCutMm, width);
        } else {
            out.widestMm = std::max(out.widestMm, width);
        }
    }
    return out;
}

} // namespace voxhap::volume
