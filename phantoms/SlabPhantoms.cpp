// SPDX-License-Identifier: Apache-2.0
/// @file SlabPhantoms.cpp
/// @brief The analytic regression phantoms: layered slab stack (physics.md §7 R1)
/// and sphere in slab (§7 R5).

#include "phantoms/Phantoms.h"

#include "core/Errors.h"

#include <cmath>
#include <sstream>

namespace voxhap::volume {

namespace {

void requirePositive(double v, const std::string& what)
{
    if (!std::isfinite(v) || v <= 0.0) throw ValueError(what + " must be positive and finite");
}

} // namespace

PhantomModel slabModel(const SlabParams& p, const TissueTable& table)
{
    if (p.layers.empty()) throw ValueError("slab phantom: no layers");
    if (!std::isfinite(p.tiltDeg) || std::abs(p.tiltDeg) > 75.0) {
        throw ValueError("slab phantom: tilt must be within ±75 degrees");
    }
    requirePositive(p.halfWidthMm, "slab phantom: half width");
    if (!std::isfinite(p.airMarginMm) || p.airMarginMm < 0.0) throw ValueError("slab phantom: air margin must be >= 0");

    // Cumulative layer bottoms along the normal, and ids resolved once.
    std::vector<double> bottoms;
    std::vector<int> ids;
    double depth = 0.0;
    std::ostringstream desc;
    desc << "slab stack, tilt " << p.tiltDeg << " deg:";
    for (const auto& layer : p.layers) {
        requirePositive(layer.thicknessMm, "slab phantom: thickness of layer '" + layer.tissue + "'");
        const Tissue& t = table.at(layer.tissue);
        if (t.id == 0) throw ValueError("slab phantom: a layer cannot be air");
        depth += layer.thicknessMm;
        bottoms.push_back(depth);
        ids.push_back(t.id);
        desc << ' ' << layer.tissue << ' ' << layer.thicknessMm << " mm";
    }
    const double total = depth;
    const double tilt = degToRad(p.tiltDeg);
    // Outward (posterior) normal of the layers; depth below the surface is -n·p.
    const Vec3d normal(0.0, std::cos(tilt), std::sin(tilt));

    PhantomModel m;
    m.kind = "slab";
    m.description = desc.str();
    m.classify = [bottoms, ids, normal](const Vec3d& w) {
        const double d = -normal.dot(w);
        if (d < 0.0) return 0;
        for (std::size_t j = 0; j < bottoms.size(); ++j) {
            if (d < bottoms[j]) return ids[j];
        }
        return 0;
    };
    const double hw = p.halfWidthMm;
    const double spread = hw * std::abs(std::sin(tilt)); // vertical reach of the tilted planes
    m.bounds = {
        Vec3d(-hw, -(total + spread) / std::cos(tilt), -hw), Vec3d(hw, spread / std::cos(tilt) + p.airMarginMm, hw)};
    m.pathEntry = Vec3d::Zero();
    m.pathTarget = -total * normal;
    m.landmarks = {{"entry", m.pathEntry}, {"bottom", m.pathTarget}};
    return m;
}

PhantomModel sphereModel(const SphereParams& p, const TissueTable& table)
{
    requirePositive(p.slabThicknessMm, "sphere phantom: slab thickness");
    requirePositive(p.radiusMm, "sphere phantom: radius");
    requirePositive(p.halfWidthMm, "sphere phantom: half width");
    if (2.0 * p.radiusMm >= p.slabThicknessMm || p.radiusMm >= p.halfWidthMm) {
        throw ValueError("sphere phantom: the sphere must fit inside the slab");
    }
    const int slab = table.at(p.slabTissue).id;
    const int sphere = table.at(p.sphereTissue).id;
    if (slab == 0 || sphere == 0) throw ValueError("sphere phantom: tissues cannot be air");
    const double t = p.slabThicknessMm, r2 = p.radiusMm * p.radiusMm;
    const Vec3d centre(0.0, -0.5 * t, 0.0);

    PhantomModel m;
    m.kind = "sphere";
    std::ostringstream desc;
    desc << "sphere of " << p.sphereTissue << " r " << p.radiusMm << " mm in " << p.slabThicknessMm << " mm of "
         << p.slabTissue;
    m.description = desc.str();
    m.classify = [=](const Vec3d& w) {
        if (w.y() > 0.0 || w.y() < -t) return 0;
        return (w - centre).squaredNorm() < r2 ? sphere : slab;
    };
    m.bounds = {Vec3d(-p.halfWidthMm, -t, -p.halfWidthMm), Vec3d(p.halfWidthMm, p.airMarginMm, p.halfWidthMm)};
    m.pathEntry = Vec3d::Zero();
    m.pathTarget = Vec3d(0.0, -t, 0.0);
    m.landmarks = {{"entry", m.pathEntry}, {"sphere_centre", centre}, {"bottom", m.pathTarget}};
    return m;
}

PhantomModel phantomModel(const PhantomSpec& spec, const TissueTable& table)
{
    if (spec.kind == "slab") return slabModel(spec.slab, table);
    if (spec.kind == "sphere") return sphereModel(spec.sphere, table);
    if (spec.kind == "lumbar") return lumbarModel(spec.lumbar, table);
    if (spec.kind == "torso") return torsoModel(spec.torso, table);
    throw ValueError("phantom: unknown kind '" + spec.kind + "' (slab, sphere, lumbar, torso)");
}

} // namespace voxhap::volume
