// SPDX-License-Identifier: Apache-2.0
/// @file Volume.cpp
/// @brief Volume: shared transform, channel checks, geometry conversions.

#include "volume/Volume.h"

#include "core/Errors.h"
#include "volume/Grids.h"

#include <cmath>
#include <mutex>

namespace voxhap::volume {

std::string_view channelName(Channel c)
{
    switch (c) {
    case Channel::Hu:
        return "hu";
    case Channel::T1:
        return "t1";
    case Channel::Label:
        return "label";
    case Channel::Intensity:
        return "intensity";
    }
    return "?";
}

void initializeOpenVdb()
{
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

openvdb::math::Transform::Ptr makeTransform(const Geometry& g)
{
    // Bounds far outside any scanner's (voxels from 1 nm to 10 m, origins within
    // 1 km): beyond them OpenVDB's map arithmetic loses the small terms and
    // throws its own errors (found by fuzz/FuzzNrrdHeader).
    constexpr double kMinSpacingMm = 1e-6, kMaxSpacingMm = 1e4, kMaxOriginMm = 1e6;
    for (int i = 0; i < 3; ++i) {
        if (!std::isfinite(g.spacing[i]) || g.spacing[i] < kMinSpacingMm || g.spacing[i] > kMaxSpacingMm) {
            throw ValueError("geometry: spacing[" + std::to_string(i) + "] = " + std::to_string(g.spacing[i]) +
                " mm is outside 1e-6 to 1e4 mm");
        }
        if (!g.origin.allFinite() || !g.direction.allFinite()) {
            throw ValueError("geometry: origin and direction must be finite");
        }
        if (std::abs(g.origin[i]) > kMaxOriginMm) {
            throw ValueError("geometry: origin[" + std::to_string(i) + "] = " + std::to_string(g.origin[i]) +
                " mm is more than 1 km from the scanner's origin");
        }
        if (std::abs(g.direction.col(i).norm() - 1.0) > 1e-6) {
            throw ValueError("geometry: direction column " + std::to_string(i) + " is not a unit vector");
        }
    }
    if (std::abs(g.direction.determinant()) < 1e-6) {
        throw ValueError("geometry: direction cosines are degenerate (determinant near 0)");
    }
    // OpenVDB composes row vectors: world = [i j k 1] · M, so M's rows hold
    // the images of the index axes and its last row the translation.
    const Mat3d a = g.direction * g.spacing.asDiagonal();
    openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) m(r, c) = a(c, r);
        m(3, r) = g.origin[r];
    }
    try {
        return openvdb::math::Transform::createLinearTransform(m);
    } catch (const openvdb::Exception& e) {
        throw ValueError(std::string("geometry: OpenVDB refuses the transform (") + e.what() + ")");
    }
}

Geometry geometryOf(const openvdb::math::Transform& xform)
{
    if (!xform.isLinear()) throw ValueError("transform: not linear (" + xform.mapType() + ")");
    const openvdb::math::Mat4d m = xform.baseMap()->getAffineMap()->getMat4();
    Geometry g;
    for (int c = 0; c < 3; ++c) {
        Vec3d axis(m(c, 0), m(c, 1), m(c, 2));
        g.spacing[c] = axis.norm();
        g.direction.col(c) = axis / g.spacing[c];
        g.origin[c] = m(3, c);
    }
    return g;
}

Volume::Volume(openvdb::math::Transform::Ptr xform, const IndexBox& box) : mTransform(std::move(xform)), mBox(box)
{
    if (!mTransform) throw ValueError("volume: null transform");
    initializeOpenVdb();
}

Volume::Volume(const Geometry& g, const IndexBox& box) : Volume(makeTransform(g), box) { }

Vec3d Volume::indexToWorld(const Vec3d& ijk) const { return fromVdb(mTransform->indexToWorld(toVdb(ijk))); }

Vec3d Volume::worldToIndex(const Vec3d& xyz) const { return fromVdb(mTransform->worldToIndex(toVdb(xyz))); }

std::array<Vec3d, 2> Volume::worldBounds() const
{
    Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::infinity());
    Vec3d hi = -lo;
    if (mBox.empty()) return {Vec3d::Zero(), Vec3d::Zero()};
    for (int corner = 0; corner < 8; ++corner) {
        Vec3d ijk;
        for (int a = 0; a < 3; ++a) {
            ijk[a] = ((corner >> a) & 1) ? mBox.max[a] + 0.5 : mBox.min[a] - 0.5;
        }
        const Vec3d w = indexToWorld(ijk);
        lo = lo.cwiseMin(w);
        hi = hi.cwiseMax(w);
    }
    return {lo, hi};
}

void Volume::setGrid(Channel c, GridPtr grid)
{
    if (!grid) {
        removeGrid(c);
        return;
    }
    const std::string name(channelName(c));
    if (c == Channel::Label) {
        auto typed = openvdb::gridPtrCast<LabelGrid>(grid);
        if (!typed) throw ValueError("volume: grid '" + name + "' must be int32, got " + grid->valueType());
        if (typed->background() != kAirLabel) throw ValueError("volume: grid 'label' background must be 0 (air)");
    } else {
        auto typed = openvdb::gridPtrCast<FloatGrid>(grid);
        if (!typed) throw ValueError("volume: grid '" + name + "' must be float, got " + grid->valueType());
        const float air = c == Channel::Hu ? kAirHu : c == Channel::T1 ? kAirT1 : kAirIntensity;
        if (typed->background() != air) {
            throw ValueError("volume: grid '" + name + "' background must be " + std::to_string(air) + " (air)");
        }
    }
    grid->setName(name);
    grid->setTransform(mTransform);
    mGrids[index(c)] = std::move(grid);
}

void Volume::setDerived(const std::string& name, GridPtr grid)
{
    for (Channel c : kChannels) {
        if (name == channelName(c)) throw ValueError("volume: '" + name + "' is a channel, not a derived grid name");
    }
    if (name.empty()) throw ValueError("volume: a derived grid needs a name");
    if (!grid) {
        removeDerived(name);
        return;
    }
    if (!openvdb::gridPtrCast<FloatGrid>(grid)) {
        throw ValueError("volume: derived grid '" + name + "' must be float, got " + grid->valueType());
    }
    grid->setName(name);
    grid->setTransform(mTransform);
    mDerived[name] = std::move(grid);
}

Volume::GridConstPtr Volume::derived(const std::string& name) const
{
    const auto it = mDerived.find(name);
    return it == mDerived.end() ? nullptr : it->second;
}

FloatGrid::ConstPtr huGrid(const Volume& v) { return openvdb::gridConstPtrCast<FloatGrid>(v.grid(Channel::Hu)); }
FloatGrid::ConstPtr t1Grid(const Volume& v) { return openvdb::gridConstPtrCast<FloatGrid>(v.grid(Channel::T1)); }
FloatGrid::ConstPtr intensityGrid(const Volume& v)
{
    return openvdb::gridConstPtrCast<FloatGrid>(v.grid(Channel::Intensity));
}
LabelGrid::ConstPtr labelGrid(const Volume& v) { return openvdb::gridConstPtrCast<LabelGrid>(v.grid(Channel::Label)); }

} // namespace voxhap::volume
