// SPDX-License-Identifier: Apache-2.0
/// @file BentNeedle.cpp
/// @brief One quasi-static solve per tick: the foundation on the track, the
/// bevel's force, the band solve, the polyline and the track's growth
/// (physics.md §9).

#include "haptic/beam/BentNeedle.h"

#include "core/Errors.h"

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

namespace {

int elementsFor(const BeamParams& p)
{
    if (!(p.lengthMm > 0.0) || !std::isfinite(p.lengthMm)) throw ValueError("needle bending: bad needle length");
    if (!(p.minNodeSpacingMm > 0.0) || p.maxNodes < 2) throw ValueError("needle bending: bad node spacing");
    const double n = std::floor(p.lengthMm / p.minNodeSpacingMm);
    return int(std::clamp(n, 1.0, double(p.maxNodes - 1)));
}

} // namespace

Vec3d bevelReferenceAxis(const Vec3d& pathDirection) noexcept
{
    const double n = pathDirection.norm();
    const Vec3d u = n > 0.0 && std::isfinite(n) ? Vec3d(pathDirection / n) : Vec3d::UnitY();
    return std::abs(u.z()) < std::cos(degToRad(25.0)) ? Vec3d::UnitZ() : Vec3d::UnitX();
}

BeamParams BeamParams::fromNeedle(const Needle& n)
{
    BeamParams p;
    p.lengthMm = n.lengthMm;
    const double e = n.youngsModulus();
    if (!(e > 0.0) || !std::isfinite(e)) throw ValueError("needle.youngs_modulus_GPa: must be positive");
    const double od = n.outerDiameterMm(), id = n.innerDiameterMm();
    if (!(id >= 0.0) || !(id < od)) {
        throw ValueError("needle.inner_diameter_mm: must be at least 0 and below the outer diameter (" +
            std::to_string(od) + " mm for " + std::to_string(n.gauge) + " G)");
    }
    if (!(n.bevelAngleDeg > 0.0 && n.bevelAngleDeg < 90.0))
        throw ValueError("needle.bevel_angle_deg: must be in (0, 90) deg");
    p.eiNmm2 = n.bendingStiffnessNmm2();
    if (n.asymmetricTip()) {
        // §9.3 [chosen]: the bevel face, D·cot α long, pressed into the foundation by
        // up to D: P = k·D·(D·cot α)/2.
        const double cotA = 1.0 / std::tan(degToRad(n.bevelAngleDeg));
        p.bevelLengthMm = od * cotA;
        p.bevelFactorMm2 = 0.5 * od * od * cotA;
    }
    p.orientationRad = degToRad(n.bevelOrientationDeg);
    return p;
}

BentNeedle::BentNeedle(const BeamParams& params, std::unique_ptr<Foundation> foundation, const Vec3d& referenceAxis)
    : mParams(params), mBeam(elementsFor(params), params.lengthMm, params.eiNmm2, /*clampedStart=*/true),
      mTrack(params.trackStepMm, params.lengthMm), mFoundation(std::move(foundation)), mReference(referenceAxis)
{
    if (!mFoundation) throw ValueError("needle bending: no foundation");
    if (!(mParams.bevelFactorMm2 >= 0.0) || !std::isfinite(mParams.bevelFactorMm2) || !(mParams.bevelLengthMm >= 0.0) ||
        !std::isfinite(mParams.orientationRad))
        throw ValueError("needle bending: bad bevel");
    if (!mReference.allFinite() || !(mReference.norm() > 0.0))
        throw ValueError("needle bending: the reference axis must be finite and non-zero");
    mReference.normalize();
    mNodes.assign(std::size_t(mBeam.elements() + 1), Vec3d::Zero());
    mAxial.assign(mNodes.size(), 0.0);
    straight();
}

BentNeedle::BentNeedle(const BentNeedle& o)
    : mParams(o.mParams), mBeam(o.mBeam), mTrack(o.mTrack), mFoundation(o.mFoundation->clone()),
      mReference(o.mReference), mRoll(o.mRoll), mHub(o.mHub), mU(o.mU), mE1(o.mE1), mE2(o.mE2), mNodes(o.mNodes),
      mAxial(o.mAxial), mTipDirection(o.mTipDirection), mBevelForce(o.mBevelForce), mHubForce(o.mHubForce),
      mHubTorque(o.mHubTorque), mInserted(o.mInserted), mHubStiffness(o.mHubStiffness), mScale(o.mScale),
      mBevelModulus(o.mBevelModulus), mAheadModulus(o.mAheadModulus), mPinned(o.mPinned), mPin(o.mPin),
      mLastHeading(o.mLastHeading)
{
}

void BentNeedle::reset() noexcept
{
    mTrack.clear();
    mPinned = false;
    straight();
}

void BentNeedle::enter(const Vec3d& entry) noexcept
{
    if (!entry.allFinite()) return;
    mTrack.start(entry, mFoundation->modulusAt(entry), mU);
    mFoundation->tissueAt(entry, mAheadModulus, mBevelModulus);
    mLastHeading = mU;
}

void BentNeedle::pinTip(const Vec3d& at) noexcept
{
    if (!at.allFinite()) return;
    mPin = at;
    mPinned = true;
}

void BentNeedle::straight() noexcept
{
    mScale = 1.0;
    const double h = mBeam.elementLengthMm();
    for (std::size_t i = 0; i < mNodes.size(); ++i) {
        mAxial[i] = double(i) * h;
        mNodes[i] = mHub + mAxial[i] * mU;
    }
    mTipDirection = mU;
    mBevelForce = mHubForce = mHubTorque = Vec3d::Zero();
    mInserted = 0.0;
    mHubStiffness = 0.0;
}

double BentNeedle::tipDeflectionMm() const noexcept
{
    const Vec3d d = tip() - mHub;
    return (d - d.dot(mU) * mU).norm();
}

bool BentNeedle::update(const Vec3d& hub, const Vec3d& direction) noexcept
{
    const double n = direction.norm();
    if (!hub.allFinite() || !direction.allFinite() || !(n > 0.0) || !std::isfinite(n)) {
        straight();
        return false;
    }
    mHub = hub;
    mU = direction / n;
    // The lateral frame: the reference axis ⟂ the shaft; another world axis if they align.
    Vec3d e1 = mReference - mReference.dot(mU) * mU;
    if (e1.norm() < 1e-3) {
        const Vec3d other = std::abs(mU.x()) < 0.9 ? Vec3d::UnitX() : Vec3d::UnitY();
        e1 = other - other.dot(mU) * mU;
    }
    mE1 = e1.normalized();
    mE2 = mU.cross(mE1);

    const double length = mParams.lengthMm;
    const double inserted = mTrack.empty() ? 0.0 : std::clamp(length - (mTrack.point(0) - hub).dot(mU), 0.0, length);
    if (!(inserted > 0.0)) {
        straight();
        return true;
    }
    mInserted = inserted;

    // The foundation over the inserted length; the shaft at x rests on the track at
    // arc length x − (L − inserted) below the skin (follow the leader, §9.3).
    // The tissue where the tip now is, in the tissue's rest frame: past the front,
    // on its uncut continuation. It holds the uncut stretch of the shaft and is what
    // the bevel presses on (the tissue at the front lags the tip by a step, which
    // made the path's error of the step's order where tissues change, §9.3).
    const double uncut = inserted - mTrack.frontMm();
    if (uncut > 0.0) mFoundation->tissueAt(mTrack.front() + uncut * mTrack.ahead(), mAheadModulus, mBevelModulus);
    mBeam.begin();
    const double from = length - inserted;
    mBeam.addFoundation(from, [&](double x, double& k, double& r1, double& r2) {
        Vec3d p;
        mTrack.sample(x - from, p, k);
        if (x - from > mTrack.frontMm()) k = mAheadModulus;
        const Vec3d d = p - hub;
        r1 = d.dot(mE1);
        r2 = d.dot(mE2);
    });
    // The bevel (§9.3): its face, b = D·cot α long, pressed into the tissue at the cut
    // front over the part of it below the skin (the first b of insertion) and not
    // backed into its own cut (retraction).
    double p = 0.0;
    if (mParams.bevelFactorMm2 > 0.0 && !mPinned) {
        const double b = mParams.bevelLengthMm;
        const double back = std::max(0.0, mTrack.frontMm() - inserted);
        const double contact = std::clamp((std::min(inserted, b) - back) / b, 0.0, 1.0);
        // The tissue the bevel presses on is where the tip now is in the tissue's rest
        // frame: past the front, along the uncut continuation (the tissue at the front
        // itself lags a step behind the tip, which made the path's error of the step's
        // order where tissues change).
        p = mBevelModulus * mParams.bevelFactorMm2 * contact;
    }
    const double phi = mParams.orientationRad + mRoll;
    const double p1 = p * std::cos(phi), p2 = p * std::sin(phi);
    mBeam.addEndForce(p1, p2);
    if (mPinned) {
        const Vec3d d = mPin - hub;
        mBeam.pinEnd(d.dot(mE1), d.dot(mE2));
    }
    if (!mBeam.solve()) {
        straight();
        return false;
    }

    // Small-slope theory holds while the shaft's slope to the hub's axis is small; a
    // solution steeper than kMaxSlope (a stiff tissue's bevel force on a thin needle,
    // a hand that levers the hub far off the track) is outside it, and is held at
    // that slope, scaled as a whole, rather than followed (physics.md §9.4).
    double steepest = 0.0;
    for (int i = 0; i <= mBeam.elements(); ++i)
        steepest = std::max(steepest, std::hypot(mBeam.slope(i, 0), mBeam.slope(i, 1)));
    mScale = steepest > kMaxSlope ? kMaxSlope / steepest : 1.0;

    // The polyline: the lateral deflections, each element kept its length along
    // the bent shaft (the axis gives way by what the deflection takes).
    const double h = mBeam.elementLengthMm();
    const auto w = [&](int node, int c) { return mScale * mBeam.deflection(node, c); };
    for (std::size_t i = 0; i < mNodes.size(); ++i) {
        const int node = int(i);
        if (i > 0) {
            const double d1 = w(node, 0) - w(node - 1, 0), d2 = w(node, 1) - w(node - 1, 1);
            mAxial[i] = mAxial[i - 1] + std::sqrt(std::max(0.0, h * h - d1 * d1 - d2 * d2));
        }
        mNodes[i] = hub + mAxial[i] * mU + w(node, 0) * mE1 + w(node, 1) * mE2;
    }
    const int last = mBeam.elements();
    mTipDirection = (mU + mScale * (mBeam.slope(last, 0) * mE1 + mBeam.slope(last, 1) * mE2)).normalized();
    mBevelForce = p1 * mE1 + p2 * mE2;
    double f1 = 0.0, f2 = 0.0, m1 = 0.0, m2 = 0.0;
    mBeam.startReaction(f1, f2, m1, m2);
    f1 *= mScale, f2 *= mScale, m1 *= mScale, m2 *= mScale;
    // The clamp's moment m_c turns the shaft toward e_c: about u × e1 = e2 and u × e2 = −e1.
    mHubForce = -(f1 * mE1 + f2 * mE2);
    mHubTorque = -(m1 * mE2 - m2 * mE1);
    mHubStiffness = mScale * mBeam.startTranslationStiffness();
    extendTrack(inserted);
    return true;
}

void BentNeedle::extendTrack(double tipTau) noexcept
{
    // The tip cuts along its heading (§9.3): the nonholonomic rule of bevel-tip
    // needles (Webster et al. 2006), the front moving on by what the tip advanced.
    if (mPinned) { // bone holds the tip: nothing is cut
        mLastHeading = mTipDirection;
        return;
    }
    (void)mTrack.cut(tipTau, mLastHeading, mTipDirection, [&](const Vec3d& p) { return mFoundation->modulusAt(p); });
    mLastHeading = mTipDirection;
}

} // namespace voxhap::haptic
