// SPDX-License-Identifier: Apache-2.0
/// @file RayMarch.cpp
/// @brief Fixed-step ray march, nearest or trilinear sampling (physics.md §7 R1).

#include "haptic/RayMarch.h"

#include "haptic/detail/FieldGrids.h"
#include "haptic/detail/LeafReader.h"
#include "haptic/detail/Traversal.h"
#include "volume/Errors.h"

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
        : mBeta(detail::dampingGrid(field)), mLabels(trackLabels ? detail::labelGrid(field) : nullptr),
          mStep(stepMm), mTrilinear(trilinear)
    {
        if (!(stepMm > 0.0) || !std::isfinite(stepMm)) throw ValueError("ray march: step must be positive");
        if (!mBeta) throw ValueError("ray march: the material field has no damping grid");
        mXform = mBeta->transformPtr();
        mBetaReader.emplace(mBeta->tree());
        if (mLabels) mLabelReader.emplace(mLabels->tree());
        // Samples beyond the active box read the background (0): march only inside it,
        // grown by one voxel for the trilinear reach.
        detail::activeBox(*mBeta, 1.0, mLo, mHi);
        if (mLabels) {
            openvdb::Vec3d lo, hi;
            detail::activeBox(*mLabels, 1.0, lo, hi);
            mLo = openvdb::math::minComponent(mLo, lo);
            mHi = openvdb::math::maxComponent(mHi, hi);
        }
        mLo -= openvdb::Vec3d(0.5); // to the unshifted frame: samples use voxel-centre coordinates
        mHi -= openvdb::Vec3d(0.5);
    }
    RayMarch(const RayMarch& o)
        : mBeta(o.mBeta), mLabels(o.mLabels), mXform(o.mXform), mStep(o.mStep), mTrilinear(o.mTrilinear), mLo(o.mLo),
          mHi(o.mHi)
    {
        mBetaReader.emplace(*o.mBetaReader);
        if (o.mLabelReader) mLabelReader.emplace(*o.mLabelReader);
    }

    void integrate(const Segment& seg, ShaftIntegral& out) noexcept override
    {
        out.reset();
        const detail::IndexSegment s = detail::toIndex(*mXform, seg, 0.0);
        out.lengthMm = s.lengthMm;
        out.labelsValid = mLabelReader.has_value();
        if (!s.valid) return;
        detail::LabelTally tally(out, s.lengthMm);
        double t0 = 0.0, t1 = 0.0;
        if (!detail::clip(s, mLo, mHi, t0, t1)) {
            if (mLabelReader) tally.add(0, 0.0, 1.0);
            return;
        }
        if (mLabelReader && t0 > 0.0) tally.add(0, 0.0, t0);
        const double span = (t1 - t0) * s.lengthMm;
        const auto n = static_cast<long>(std::max(1.0, std::ceil(span / mStep)));
        const double dt = (t1 - t0) / double(n);
        double sum = 0.0;
        for (long i = 0; i <= n; ++i) {
            const double t = t0 + dt * double(i);
            const double w = (i == 0 || i == n) ? 0.5 : 1.0; // trapezoid weights
            const openvdb::Vec3d p = s.a + s.d * t;
            const double b = mTrilinear ? trilinear(p) : nearestValue(*mBetaReader, p);
            sum += w * b;
            if (mLabelReader) {
                // Each sample owns the weight of its trapezoid share of the path.
                const double ta = std::max(t0, t - 0.5 * dt), tb = std::min(t1, t + 0.5 * dt);
                tally.add(nearestLabel(*mLabelReader, p), ta, tb);
            }
        }
        if (mLabelReader && t1 < 1.0) tally.add(0, t1, 1.0);
        out.dampingIntegral = sum * dt * s.lengthMm;
    }
    std::unique_ptr<ShaftIntegrator> clone() const override { return std::make_unique<RayMarch>(*this); }
    std::string name() const override
    {
        std::ostringstream os;
        os << (mTrilinear ? "march-trilinear" : "march-nearest") << " h=" << mStep << "mm";
        return os.str();
    }

private:
    double trilinear(const openvdb::Vec3d& p) noexcept
    {
        const openvdb::Coord c = openvdb::Coord::floor(p);
        const double u = p[0] - c.x(), v = p[1] - c.y(), w = p[2] - c.z();
        double k[8];
        detail::loadCorners(*mBetaReader, c, k);
        return detail::trilinear(k, u, v, w);
    }

    FloatGrid::ConstPtr mBeta;
    LabelGrid::ConstPtr mLabels;
    openvdb::math::Transform::ConstPtr mXform;
    double mStep;
    bool mTrilinear;
    openvdb::Vec3d mLo{1.0}, mHi{-1.0};
    std::optional<detail::LeafReader<FloatGrid::TreeType>> mBetaReader;
    std::optional<detail::LeafReader<LabelGrid::TreeType>> mLabelReader;
};

} // namespace

std::unique_ptr<ShaftIntegrator> makeRayMarch(const MaterialField& field, double stepMm, bool trilinear,
                                              bool trackLabels)
{
    return std::make_unique<RayMarch>(field, stepMm, trilinear, trackLabels);
}

} // namespace voxhap::haptic
