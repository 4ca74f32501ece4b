// SPDX-License-Identifier: Apache-2.0
/// @file Traversal.h
/// @brief The shared machinery of the shaft integrators: a world segment in
/// index space, clipping to the active box, and the Amanatides–Woo walk
/// (openvdb::math::DDA) over voxel cells or trilinear cells.
///
/// Segments are parameterised by t in [0, 1] from entry to tip. The index map
/// is affine, so a t-interval of length dt is exactly dt·L millimetres of
/// shaft whatever the voxel anisotropy: chords are never measured in index
/// units (architecture.md "Index versus world").
#pragma once

#include "haptic/shaft/ShaftIntegration.h"
#include "haptic/shaft/detail/LeafReader.h"
#include "volume/Grids.h"

#include <openvdb/math/DDA.h>
#include <openvdb/math/Ray.h>

#include <algorithm>
#include <cmath>
#include <span>

namespace voxhap::haptic::detail {

using RayT = openvdb::math::Ray<double>;

/// @brief A shaft in index space: p(t) = a + t·d, t in [0, 1].
struct IndexSegment {
    openvdb::Vec3d a{0.0}, d{0.0};
    double lengthMm = 0; ///< world length: t-interval dt is dt·lengthMm millimetres
    bool valid = false;  ///< finite input and non-zero length
};

/// @brief A grid's world-to-index map held by value: a volume's transform is
/// affine, and its matrix applied directly spares the two virtual calls per
/// point of openvdb::math::Transform (a shaft converts two points per tick).
class AffineIndexMap {
public:
    AffineIndexMap() = default;
    explicit AffineIndexMap(const openvdb::math::Transform& xf)
        : mLinear(xf.isLinear()), mAffine(*xf.baseMap()->getAffineMap()), mTransform(xf.copy())
    {
    }
    openvdb::Vec3d worldToIndex(const openvdb::Vec3d& p) const noexcept
    {
        return mLinear ? mAffine.applyInverseMap(p) : mTransform->worldToIndex(p);
    }

private:
    bool mLinear = true;
    openvdb::math::AffineMap mAffine;
    openvdb::math::Transform::ConstPtr mTransform;
};

/// @brief Convert a world segment; @p shift is added to index coordinates
/// (0.5 for voxel cells, whose centres are integers, so that floor() finds
/// the cell; 0 for trilinear cells, whose corners are voxel centres).
/// @p xf: an openvdb::math::Transform or an AffineIndexMap.
template <typename IndexMap> inline IndexSegment toIndex(const IndexMap& xf, const Segment& s, double shift) noexcept
{
    IndexSegment out;
    if (!s.entry.allFinite() || !s.tip.allFinite()) return out;
    out.lengthMm = (s.tip - s.entry).norm();
    if (!(out.lengthMm > 0.0) || !std::isfinite(out.lengthMm)) {
        out.lengthMm = std::isfinite(out.lengthMm) ? out.lengthMm : 0.0;
        return out;
    }
    const openvdb::Vec3d a = xf.worldToIndex(volume::toVdb(s.entry)) + openvdb::Vec3d(shift);
    const openvdb::Vec3d b = xf.worldToIndex(volume::toVdb(s.tip)) + openvdb::Vec3d(shift);
    out.a = a;
    out.d = b - a;
    // A component many orders below the others cannot cross a face within the
    // segment, but its reciprocal can overflow the DDA's arithmetic: zero it
    // (the DDA disables zero axes exactly).
    const double scale = std::max({std::abs(out.d[0]), std::abs(out.d[1]), std::abs(out.d[2])});
    for (int i = 0; i < 3; ++i) {
        if (std::abs(out.d[i]) < 1e-13 * scale) out.d[i] = 0.0;
    }
    out.valid = scale > 0.0;
    return out;
}

/// @brief Clip [0, 1] to the t-range inside the box [lo, hi] (index space,
/// slab method). @return false if the segment misses the box.
inline bool clip(
    const IndexSegment& s, const openvdb::Vec3d& lo, const openvdb::Vec3d& hi, double& t0, double& t1) noexcept
{
    t0 = 0.0;
    t1 = 1.0;
    for (int i = 0; i < 3; ++i) {
        if (s.d[i] == 0.0) {
            if (s.a[i] < lo[i] || s.a[i] > hi[i]) return false;
            continue;
        }
        double ta = (lo[i] - s.a[i]) / s.d[i];
        double tb = (hi[i] - s.a[i]) / s.d[i];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    return t0 < t1;
}

/// @brief Walk the unit cells [c, c+1)³ met by s over [t0, t1], calling
/// visit(cell, ta, tb) for each with tb > ta (a cell touched only at an edge
/// or corner has a zero chord and is skipped). Ties between axes go to the
/// lowest axis index (openvdb::math::MinIndex): deterministic.
template <typename Visit> inline void walkCells(const IndexSegment& s, double t0, double t1, Visit&& visit) noexcept
{
    const RayT ray(s.a, s.d, 0.0, 1.0);
    openvdb::math::DDA<RayT, 0> dda(ray, t0, t1);
    do {
        const double ta = dda.time();
        const double tb = dda.next();
        if (tb > ta) visit(dda.voxel(), ta, tb);
    } while (dda.step());
}

/// @brief walkCells() that crosses uniform regions in one step: where
/// uniform(cell) returns a block side dim > 1, every cell up to the exit of the
/// aligned dim³ block (less @p shrink cells on its upper side, for trilinear
/// cells whose far corners must stay inside) is handed to run(cell, ta, tExit)
/// at once. Phantoms and air are mostly uniform tiles; dense CT leaves are not.
template <typename Uniform, typename Visit, typename Run>
inline void walkCellsSkipping(
    const IndexSegment& s, double t0, double t1, int shrink, Uniform&& uniform, Visit&& visit, Run&& run) noexcept
{
    const RayT ray(s.a, s.d, 0.0, 1.0);
    openvdb::math::DDA<RayT, 0> dda(ray, t0, t1);
    for (;;) {
        const openvdb::Coord c = dda.voxel();
        const double ta = dda.time();
        if (const int dim = uniform(c); dim > 1) {
            double exit = t1;
            for (int i = 0; i < 3; ++i) {
                if (s.d[i] == 0.0) continue;
                const int lo = c[i] & ~(dim - 1);
                const double face = s.d[i] > 0.0 ? double(lo + dim - shrink) : double(lo);
                exit = std::min(exit, (face - s.a[i]) / s.d[i]);
            }
            // Round-off can put the restarted walk a hair before the block's face:
            // then exit <= ta and the cell is visited the ordinary way.
            if (exit > ta) {
                run(c, ta, exit);
                if (exit >= t1) return;
                dda.init(ray, exit, t1);
                continue;
            }
        }
        const double tb = dda.next();
        if (tb > ta) visit(c, ta, tb);
        if (!dda.step()) return;
    }
}

/// @brief The index-space box of a grid's active voxels as voxel cells in the
/// shifted (+0.5) frame, grown by @p pad cells; empty grids give lo > hi.
inline void activeBox(const openvdb::GridBase& g, double pad, openvdb::Vec3d& lo, openvdb::Vec3d& hi)
{
    const openvdb::CoordBBox bb = g.evalActiveVoxelBoundingBox();
    if (bb.empty()) {
        lo = openvdb::Vec3d(1.0);
        hi = openvdb::Vec3d(-1.0);
        return;
    }
    lo = bb.min().asVec3d() - openvdb::Vec3d(pad);
    hi = bb.max().asVec3d() + openvdb::Vec3d(1.0 + pad);
}

/// @brief Accumulates label lengths and first hits, the air outside the box included.
/// @p offsetMm: where the segment starts along a polyline (first hits are measured from its start).
class LabelTally {
public:
    explicit LabelTally(ShaftIntegral& out, double lengthMm, double offsetMm = 0.0) noexcept
        : mOut(out), mLength(lengthMm), mOffset(offsetMm)
    {
    }
    void add(int label, double ta, double tb) noexcept
    {
        if (static_cast<unsigned>(label) >= static_cast<unsigned>(kMaxLabels)) label = 0;
        mOut.labelLengthMm[std::size_t(label)] += (tb - ta) * mLength;
        double& hit = mOut.firstHitMm[std::size_t(label)];
        if (hit == kNotHit) hit = mOffset + ta * mLength;
    }

private:
    ShaftIntegral& mOut;
    double mLength;
    double mOffset;
};

/// @brief Every point of a polyline is finite and there is at least one segment.
inline bool polylineValid(std::span<const Vec3d> points) noexcept
{
    if (points.size() < 2) return false;
    for (const Vec3d& p : points) {
        if (!p.allFinite()) return false;
    }
    return true;
}

/// @brief Run @p pass(segment, offsetMm) over each segment of non-zero length of
/// a polyline (points checked with polylineValid), offsetMm being the length
/// before it; the damping each pass leaves in out.dampingIntegral is summed.
/// out.lengthMm becomes the polyline's length.
template <typename IndexMap, typename Pass>
inline void eachSegment(
    const IndexMap& xf, std::span<const Vec3d> points, double shift, ShaftIntegral& out, Pass&& pass) noexcept
{
    double offset = 0.0, damping = 0.0;
    for (std::size_t i = 1; i < points.size(); ++i) {
        const IndexSegment s = toIndex(xf, Segment{points[i - 1], points[i]}, shift);
        if (!s.valid) continue;
        out.dampingIntegral = 0.0;
        pass(s, offset);
        damping += out.dampingIntegral;
        offset += s.lengthMm;
    }
    out.dampingIntegral = damping;
    out.lengthMm = offset;
}

/// @brief The 8 values at the corners c + {0,1}³ of a trilinear cell; corner i is
/// (i>>2 & 1, i>>1 & 1, i & 1). Non-finite voxels read as 0.
template <typename Reader> inline void loadCorners(Reader& r, const openvdb::Coord& c, double (&corner)[8]) noexcept
{
    constexpr int kLast = 7; // a cell whose lower corner is not on a leaf's last plane has all 8 in that leaf
    if ((c.x() & kLast) != kLast && (c.y() & kLast) != kLast && (c.z() & kLast) != kLast) {
        if (const auto* data = r.leafData(c)) {
            const openvdb::Index o = openvdb::Index(((c.x() & kLast) << 6) | ((c.y() & kLast) << 3) | (c.z() & kLast));
            static constexpr openvdb::Index kStep[8] = {0, 1, 8, 9, 64, 65, 72, 73};
            for (int i = 0; i < 8; ++i) {
                const auto v = data[o + kStep[i]];
                corner[i] = std::isfinite(v) ? double(v) : 0.0;
            }
            return;
        }
    }
    for (int i = 0; i < 8; ++i) {
        const float v = r.get(c.offsetBy((i >> 2) & 1, (i >> 1) & 1, i & 1));
        corner[i] = std::isfinite(v) ? double(v) : 0.0;
    }
}

/// @brief Trilinear interpolation of loadCorners() values at local (u, v, w) in [0, 1]³.
inline double trilinear(const double (&c)[8], double u, double v, double w) noexcept
{
    const double c00 = c[0] + (c[4] - c[0]) * u, c01 = c[1] + (c[5] - c[1]) * u;
    const double c10 = c[2] + (c[6] - c[2]) * u, c11 = c[3] + (c[7] - c[3]) * u;
    const double c0 = c00 + (c10 - c00) * v, c1 = c01 + (c11 - c01) * v;
    return c0 + (c1 - c0) * w;
}

} // namespace voxhap::haptic::detail
