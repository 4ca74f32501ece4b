// SPDX-License-Identifier: Apache-2.0
/// @file BlockDdaPeer.cpp
/// @brief The two-level OpenVDB block walk (see the header).

#include "bench/BlockDdaPeer.h"

#include "core/Errors.h"
#include "volume/Grids.h"

#include <openvdb/math/DDA.h>
#include <openvdb/math/Ray.h>

#include <algorithm>
#include <cmath>

namespace voxhap::bench {

using RayT = openvdb::math::Ray<double>;
using TreeT = volume::FloatGrid::TreeType;
using LeafT = TreeT::LeafNodeType;

struct BlockDdaPeer::Impl {
    explicit Impl(volume::FloatGrid::ConstPtr g)
        : grid(std::move(g)), acc(grid->tree()), affine(*grid->transform().baseMap()->getAffineMap())
    {
        const openvdb::CoordBBox bb = grid->evalActiveVoxelBoundingBox();
        // Voxel cells in the frame shifted by +0.5, where cell c = floor(p).
        lo = bb.min().asVec3d();
        hi = bb.max().asVec3d() + openvdb::Vec3d(1.0);
        empty = bb.empty();
    }
    volume::FloatGrid::ConstPtr grid;
    openvdb::tree::ValueAccessor<const TreeT> acc;
    openvdb::Vec3d lo, hi;
    bool empty = true;
    openvdb::math::AffineMap affine; ///< the grid's (affine) map by value: no virtual calls per point
};

BlockDdaPeer::BlockDdaPeer(const haptic::MaterialField& field)
{
    auto beta = openvdb::gridConstPtrCast<volume::FloatGrid>(field.damping());
    if (!beta) throw ValueError("block DDA peer: the material field has no damping grid");
    mImpl = std::make_unique<Impl>(beta);
}

BlockDdaPeer::~BlockDdaPeer() = default;

double BlockDdaPeer::integrate(const haptic::Segment& s) noexcept
{
    Impl& m = *mImpl;
    const double length = (s.tip - s.entry).norm();
    if (m.empty || !(length > 0.0) || !std::isfinite(length)) return 0.0;
    const openvdb::Vec3d a = m.affine.applyInverseMap(volume::toVdb(s.entry)) + openvdb::Vec3d(0.5);
    openvdb::Vec3d d = m.affine.applyInverseMap(volume::toVdb(s.tip)) + openvdb::Vec3d(0.5) - a;
    const double scale = std::max({std::abs(d[0]), std::abs(d[1]), std::abs(d[2])});
    for (int i = 0; i < 3; ++i) {
        if (std::abs(d[i]) < 1e-13 * scale) d[i] = 0.0; // as haptic's toIndex: no reciprocal overflow
    }
    // Clip t in [0, 1] to the active box (slab method).
    double t0 = 0.0, t1 = 1.0;
    for (int i = 0; i < 3; ++i) {
        if (d[i] == 0.0) {
            if (a[i] < m.lo[i] || a[i] > m.hi[i]) return 0.0;
            continue;
        }
        double ta = (m.lo[i] - a[i]) / d[i], tb = (m.hi[i] - a[i]) / d[i];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    if (!(t0 < t1)) return 0.0;
    const RayT ray(a, d, 0.0, 1.0);
    openvdb::math::DDA<RayT, LeafT::LOG2DIM> block(ray, t0, t1);
    double sum = 0.0;
    do {
        const double ta = block.time(), tb = block.next();
        if (!(tb > ta)) continue;
        if (const LeafT* leaf = m.acc.probeConstLeaf(block.voxel())) {
            const float* data = leaf->buffer().data();
            openvdb::math::DDA<RayT, 0> voxel(ray, ta, tb);
            do {
                const double va = voxel.time(), vb = voxel.next();
                if (vb > va) {
                    const float v = data[LeafT::coordToOffset(voxel.voxel())];
                    if (std::isfinite(v)) sum += double(v) * (vb - va);
                }
            } while (voxel.step());
        } else {
            const float v = m.acc.getValue(block.voxel());
            if (std::isfinite(v)) sum += double(v) * (tb - ta);
        }
    } while (block.step());
    return sum * length;
}

} // namespace voxhap::bench
