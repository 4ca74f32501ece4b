// SPDX-License-Identifier: Apache-2.0
/// @file ExactTraversal.cpp
/// @brief The exact strategies: chord-weighted voxel traversal (physics.md §1.2
/// [chosen], exact for a piecewise-constant field) and its trilinear twin.

#include "haptic/shaft/ExactTraversal.h"

#include "core/Errors.h"
#include "haptic/shaft/detail/FieldReaders.h"

#include <optional>

namespace voxhap::haptic {

namespace {

using detail::FieldReaders;
using detail::IndexSegment;

/// Readers plus the boxes both exact strategies clip to.
struct Sources : FieldReaders {
    Sources(const MaterialField& field, bool trackLabels, bool needDamping)
        : FieldReaders(field, trackLabels, needDamping, "shaft integration")
    {
        box(0.0, voxelLo, voxelHi);
        if (beta) { // trilinear cells, unshifted: the field reaches one voxel past the active ones
            detail::activeBox(*beta, 0.5, cellLo, cellHi);
            cellLo -= openvdb::Vec3d(0.5);
            cellHi -= openvdb::Vec3d(0.5);
        }
    }
    openvdb::Vec3d voxelLo{1.0}, voxelHi{-1.0}; // voxel cells, shifted (+0.5) frame
    openvdb::Vec3d cellLo{1.0}, cellHi{-1.0};   // trilinear cells, unshifted frame
};

/// Shared start of integrate(): reset, length, validity.
inline bool begin(const Sources& src, const Segment& seg, double shift, IndexSegment& s, ShaftIntegral& out) noexcept
{
    out.reset(src.labelReader.has_value());
    s = detail::toIndex(src.indexMap, seg, shift);
    out.lengthMm = s.lengthMm;
    out.labelsValid = src.labelReader.has_value();
    return s.valid;
}

/// Walk the voxel cells of s: chord-weighted β (if wanted) and label tally; @p offsetMm
/// is where s starts along a polyline.
void voxelPass(Sources& src, const IndexSegment& s, bool wantBeta, ShaftIntegral& out, double offsetMm = 0.0) noexcept
{
    detail::chordPass(
        s, src.voxelLo, src.voxelHi, wantBeta ? src.betaCursorPtr() : nullptr, src.labelCursorPtr(), out, offsetMm);
}

/// Shared start of integratePolyline(): reset, and whether the points make a shaft.
inline bool beginPolyline(const Sources& src, std::span<const Vec3d> points, ShaftIntegral& out) noexcept
{
    out.reset(src.labelReader.has_value());
    out.labelsValid = src.labelReader.has_value();
    return detail::polylineValid(points);
}

class ExactVoxel final : public ShaftIntegrator {
public:
    ExactVoxel(const MaterialField& field, bool trackLabels) : mSrc(field, trackLabels, false) { }

    void integrate(const Segment& seg, ShaftIntegral& out) noexcept override
    {
        IndexSegment s;
        if (begin(mSrc, seg, 0.5, s, out)) voxelPass(mSrc, s, true, out);
    }
    void integratePolyline(std::span<const Vec3d> points, ShaftIntegral& out) noexcept override
    {
        if (!beginPolyline(mSrc, points, out)) return;
        detail::eachSegment(mSrc.indexMap, points, 0.5, out,
            [&](const IndexSegment& s, double offset) { voxelPass(mSrc, s, true, out, offset); });
    }
    std::unique_ptr<ShaftIntegrator> clone() const override { return std::make_unique<ExactVoxel>(*this); }
    std::string name() const override { return "exact-voxel"; }

private:
    Sources mSrc;
};

class ExactTrilinear final : public ShaftIntegrator {
public:
    ExactTrilinear(const MaterialField& field, bool trackLabels) : mSrc(field, trackLabels, true) { }

    void integrate(const Segment& seg, ShaftIntegral& out) noexcept override
    {
        IndexSegment cells;
        if (!begin(mSrc, seg, 0.0, cells, out)) return;
        if (mSrc.labelReader) voxelPass(mSrc, detail::toIndex(mSrc.indexMap, seg, 0.5), false, out);
        out.dampingIntegral = cellSum(cells);
    }
    void integratePolyline(std::span<const Vec3d> points, ShaftIntegral& out) noexcept override
    {
        if (!beginPolyline(mSrc, points, out)) return;
        if (mSrc.labelReader) {
            detail::eachSegment(mSrc.indexMap, points, 0.5, out,
                [&](const IndexSegment& s, double offset) { voxelPass(mSrc, s, false, out, offset); });
        }
        detail::eachSegment(mSrc.indexMap, points, 0.0, out,
            [&](const IndexSegment& cells, double) { out.dampingIntegral = cellSum(cells); });
    }
    std::unique_ptr<ShaftIntegrator> clone() const override { return std::make_unique<ExactTrilinear>(*this); }
    std::string name() const override { return "exact-trilinear"; }

private:
    /// ∫β [N·s/mm] over the trilinear cells of one segment (unshifted frame).
    double cellSum(const IndexSegment& cells) noexcept
    {
        double t0 = 0.0, t1 = 0.0;
        if (!detail::clip(cells, mSrc.cellLo, mSrc.cellHi, t0, t1)) return 0.0;
        // Along a chord the trilinear field is a cubic in t; two-point Gauss–Legendre
        // quadrature is exact for cubics, so each cell's integral is exact.
        constexpr double kGauss = 0.57735026918962576451; // 1/sqrt(3)
        detail::FloatReader& r = *mSrc.betaReader;
        double sum = 0.0;
        const auto cell = [&](const openvdb::Coord& c, double ta, double tb) {
            double corner[8];
            detail::loadCorners(r, c, corner);
            const double mid = 0.5 * (ta + tb), half = 0.5 * (tb - ta) * kGauss;
            const openvdb::Vec3d origin = c.asVec3d();
            const openvdb::Vec3d p = cells.a + cells.d * (mid - half) - origin;
            const openvdb::Vec3d q = cells.a + cells.d * (mid + half) - origin;
            sum += 0.5 * (tb - ta) *
                (detail::trilinear(corner, p[0], p[1], p[2]) + detail::trilinear(corner, q[0], q[1], q[2]));
        };
        // A cell is uniform when its 8 corners share one uniform block: not on the block's last plane.
        const auto uniform = [&](const openvdb::Coord& c) {
            const int dim = r.uniformBlock(c);
            const int last = dim - 1;
            return dim > 1 && (c.x() & last) != last && (c.y() & last) != last && (c.z() & last) != last ? dim : 0;
        };
        const auto run = [&](const openvdb::Coord& c, double ta, double tb) {
            const float v = r.get(c);
            if (std::isfinite(v)) sum += double(v) * (tb - ta);
        };
        detail::walkCellsSkipping(cells, t0, t1, 1, uniform, cell, run);
        return sum * cells.lengthMm;
    }

    Sources mSrc;
};

} // namespace

std::unique_ptr<ShaftIntegrator> makeExactVoxel(const MaterialField& field, bool trackLabels)
{
    return std::make_unique<ExactVoxel>(field, trackLabels);
}

std::unique_ptr<ShaftIntegrator> makeExactTrilinear(const MaterialField& field, bool trackLabels)
{
    return std::make_unique<ExactTrilinear>(field, trackLabels);
}

} // namespace voxhap::haptic
