// SPDX-License-Identifier: Apache-2.0
/// @file RayMarch.cpp
/// @brief Fixed-step ray march, nearest or trilinear sampling (physics.md §7 R1).

#include "haptic/shaft/RayMarch.h"

#include "core/Errors.h"
#include "haptic/shaft/detail/FieldReaders.h"

#include <optional>
#include <sstream>

namespace voxhap::haptic {

namespace {

using detail::FloatGrid;
using detail::LabelGrid;

/// The value of the voxel whose centre is nearest to index point p; non-finite β reads as 0.
inline double nearestValue(detail::LeafReader<FloatGrid::TreeType>& r, const openvdb::Vec3d& p) noexcept
{
    const float v = r.get(openvdb::Coord::floor(p + openvdb::Vec3d(0.5)));
    return std::isfinite(v) ? double(v) : 0.0;
}
inline int nearestLabel(detail::LeafReader<LabelGrid::TreeType>& r, const openvdb::Vec3d& p) noexcept
{
    return r.get(openvdb::Coord::floor(p + openvdb::Vec3d(0.5)));
}

class RayMarch final : public ShaftIntegrator {
public:
    RayMarch(const MaterialField& field, double stepMm, bool trilinear, bool trackLabels)
        : mSrc(field, trackLabels, true, "ray march"), mStep(stepMm), mTrilinear(trilinear)
    {
        if (!(stepMm > 0.0) || !std::isfinite(stepMm)) throw ValueError("ray march: step must be positive");
        // Samples beyond the active box read the background (0): march only inside it,
        // grown by one voxel for the trilinear reach, in the unshifted frame of voxel centres.
        mSrc.box(1.0, mLo, mHi);
        mLo -= openvdb::Vec3d(0.5);
        mHi -= openvdb::Vec3d(0.5);
    }

    void integrate(const Segment& seg, ShaftIntegral& out) noexcept override
    {
        out.reset();
        const detail::IndexSegment s = detail::toIndex(*mSrc.xform, seg, 0.0);
        out.lengthMm = s.lengthMm;
        out.labelsValid = mSrc.labelReader.has_value();
        if (!s.valid) return;
        march(s, out, 0.0);
    }
    void integratePolyline(std::span<const Vec3d> points, ShaftIntegral& out) noexcept override
    {
        out.reset();
        out.labelsValid = mSrc.labelReader.has_value();
        if (!detail::polylineValid(points)) return;
        detail::eachSegment(*mSrc.xform, points, 0.0, out,
            [&](const detail::IndexSegment& s, double offset) { march(s, out, offset); });
    }
    std::unique_ptr<ShaftIntegrator> clone() const override { return std::make_unique<RayMarch>(*this); }
    std::string name() const override
    {
        std::ostringstream os;
        os << (mTrilinear ? "march-trilinear" : "march-nearest") << " h=" << mStep << "mm";
        return os.str();
    }

private:
    /// One segment s (valid), starting @p offset mm along the shaft: labels into
    /// @p out, ∫β into out.dampingIntegral.
    void march(const detail::IndexSegment& s, ShaftIntegral& out, double offset) noexcept
    {
        detail::LabelTally tally(out, s.lengthMm, offset);
        double t0 = 0.0, t1 = 0.0;
        if (!detail::clip(s, mLo, mHi, t0, t1)) {
            if (mSrc.labelReader) tally.add(0, 0.0, 1.0);
            return;
        }
        if (mSrc.labelReader && t0 > 0.0) tally.add(0, 0.0, t0);
        const double span = (t1 - t0) * s.lengthMm;
        const auto n = static_cast<long>(std::max(1.0, std::ceil(span / mStep)));
        const double dt = (t1 - t0) / double(n);
        double sum = 0.0;
        for (long i = 0; i <= n; ++i) {
            const double t = t0 + dt * double(i);
            const double w = (i == 0 || i == n) ? 0.5 : 1.0; // trapezoid weights
            const openvdb::Vec3d p = s.a + s.d * t;
            const double b = mTrilinear ? trilinear(p) : nearestValue(*mSrc.betaReader, p);
            sum += w * b;
            if (mSrc.labelReader) {
                // Each sample owns the weight of its trapezoid share of the path.
                const double ta = std::max(t0, t - 0.5 * dt), tb = std::min(t1, t + 0.5 * dt);
                tally.add(nearestLabel(*mSrc.labelReader, p), ta, tb);
            }
        }
        if (mSrc.labelReader && t1 < 1.0) tally.add(0, t1, 1.0);
        out.dampingIntegral = sum * dt * s.lengthMm;
    }

    double trilinear(const openvdb::Vec3d& p) noexcept
    {
        const openvdb::Coord c = openvdb::Coord::floor(p);
        const double u = p[0] - c.x(), v = p[1] - c.y(), w = p[2] - c.z();
        double k[8];
        detail::loadCorners(*mSrc.betaReader, c, k);
        return detail::trilinear(k, u, v, w);
    }

    detail::FieldReaders mSrc;
    double mStep;
    bool mTrilinear;
    openvdb::Vec3d mLo{1.0}, mHi{-1.0};
};

} // namespace

std::unique_ptr<ShaftIntegrator> makeRayMarch(
    const MaterialField& field, double stepMm, bool trilinear, bool trackLabels)
{
    return std::make_unique<RayMarch>(field, stepMm, trilinear, trackLabels);
}

} // namespace voxhap::haptic
