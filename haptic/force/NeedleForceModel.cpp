// SPDX-License-Identifier: Apache-2.0
/// @file NeedleForceModel.cpp
/// @brief The force pipeline of one tick (architecture.md; physics.md §1–§4, §6).

#include "haptic/force/NeedleForceModel.h"

#include "core/Errors.h"

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

namespace {

double orDevice(double v, double device) { return v > 0.0 ? v : device; }

/// The component of @p v perpendicular to the unit vector @p u.
Vec3d lateralOf(const Vec3d& v, const Vec3d& u) noexcept { return v - v.dot(u) * u; }

} // namespace

NeedleForceModel::NeedleForceModel(ForceModelSetup setup)
    : mState(std::move(setup.layers)), mPath(setup.path), mTerms(setup.terms), mNeedle(setup.needle),
      mDevice(setup.device), mIntegrator(std::move(setup.integrator)), mLocked(std::move(setup.locked)),
      mField(setup.field), mProxy(orDevice(mTerms.couplingNPerMm, mDevice.maxStiffnessNPerMm)), mLor(mTerms.lor.params),
      mPivot(mTerms.pivot.params), mSafety(SafetyParams::fromDevice(mDevice))
{
    const double n = mPath.direction.norm();
    if (!mPath.origin.allFinite() || !mPath.direction.allFinite() || !(n > 0.0)) {
        throw ValueError("needle path: origin and direction must be finite and the direction non-zero");
    }
    mPath.direction = mPath.direction / n;
    if (!std::isfinite(mTerms.renderScale) || !(mTerms.renderScale > 0.0))
        throw ValueError("force model: the force scale must be positive and finite");
    // Kyung's gravity compensation F_G = −m·g (physics.md §1.1 Eq. 1): the device holds up
    // its handle, so F_G points against gravity.
    const Vec3d down(mDevice.down[0], mDevice.down[1], mDevice.down[2]);
    if (!std::isfinite(mDevice.handleMassKg) || mDevice.handleMassKg < 0.0)
        throw ValueError("device: handle_mass_kg must be finite and not negative");
    if (mDevice.handleMassKg > 0.0) {
        if (!down.allFinite() || !(down.norm() > 0.0))
            throw ValueError("device: the direction of gravity must be finite and non-zero");
        mGravity = -mDevice.handleMassKg * kStandardGravityMPerS2 * down.normalized();
    }
    if (mTerms.damping.on && !mIntegrator) throw ValueError("force model: voxel damping needs a shaft integrator");
    if (mTerms.palpation.on) {
        if (!setup.skin) throw ValueError("force model: palpation needs a skin map");
        mPalp.emplace(std::move(setup.skin));
    }
    if (mTerms.guidance.on)
        mGuide.emplace(
            mTerms.guidance.params, setup.guide.value_or(GuideLine{mPath.origin, mPath.origin + mPath.direction}));
    if (mTerms.bending.on) {
        // §9.5: the beam's foundation holds the shaft where the pivot correction did, and
        // the lock's straight line is one a bent shaft leaves.
        if (mTerms.lock.on || mTerms.pivot.on)
            throw ValueError("force model: bending replaces the pivot correction and cannot run beside the lock");
        if (!setup.foundation) throw ValueError("force model: bending needs the tissue's foundation");
        mBeam = std::make_unique<BentNeedle>(
            BeamParams::fromNeedle(mNeedle), std::move(setup.foundation), bevelReferenceAxis(mPath.direction));
    }
    mIntegral.reset();
}

void NeedleForceModel::reset() noexcept
{
    mState.reset();
    mProxy.reset();
    mLor.reset();
    mPivot.reset();
    mSafety.reset();
    mIntegral.reset();
    mInContact = false;
    mCritical = false;
    mLimited = false;
    mLockAnchor = Vec3d::Zero();
    if (mPalp) mPalp->reset();
    if (mGuide) mGuide->reset();
    if (mBeam) mBeam->reset();
    mPalpating = false;
    mLastDirection = 1;
    mLastTimeS = 0;
}

bool tipInBone(const TipState& tip, const std::vector<Layer>& layers) noexcept
{
    if (tip.boneLayer >= 0) return true;
    const int current = tip.currentLayer();
    return current >= 0 && std::size_t(current) < layers.size() && layers[std::size_t(current)].role == LayerRole::Bone;
}

double tipSlipForceN(const ForceTerms& terms, const TipState& tip, const std::vector<Layer>& layers, double v) noexcept
{
    const int current = tip.currentLayer();
    if (current < 0) return 0.0;
    double f = 0.0;
    if (terms.cutting) {
        f += tip.cuttingSumN; // §2.1 Eq. 3, nested boxes
        if (tip.pushLayer < 0 && tip.inLayer >= 0)
            f += layers[std::size_t(tip.inLayer)].plateauN(tip.plateauDepthMm);                   // §3.1
        if (std::abs(v) >= terms.karnoppDeltaVMmPerS) f += layers[std::size_t(current)].coulombN; // §4 Eq. 3
    }
    // [LP] bone texture (§4): f = −c·sgn(v) for |v| > 0, else 0. A Coulomb-type term:
    // the proxy gives it the sign of the motion (§6.2).
    if (terms.boneTexture.on && v != 0.0 && tipInBone(tip, layers)) f += terms.boneTexture.cN;
    return f;
}

DampingSplit splitDamping(const ForceTerms::Damping& damping, const DeviceLimits& device, double b, double v) noexcept
{
    if (!(v > 0.0)) return {};
    b = std::max(0.0, b);
    const double rendered = std::min(b, device.maxDampingNsPerMm);
    DampingSplit s;
#ifdef VOXHAP_MUTANT_SPLIT_DAMPING
    // A deliberately wrong split, compiled only into tests/regress's mutant test: the
    // viscous part ignores the device's limit, so the excess counts twice. §7 R1 and R5
    // must catch it.
    s.viscousN = std::min(b * v, damping.capN);
#else
    s.viscousN = std::min(rendered * v, damping.capN);
#endif
    s.frictionN = std::clamp((b - rendered) * damping.referenceSpeedMmPerS, 0.0, damping.capN - s.viscousN);
    return s;
}

bool NeedleForceModel::touchingCritical() const noexcept
{
    const TipState& tip = mState.tip();
    const auto& layers = mState.layers();
    for (int i = 0; i <= tip.inLayer; ++i) {
        if (layers[std::size_t(i)].role == LayerRole::Critical && mState.state(i) == LayerState::Punctured) return true;
    }
    if (mField && mIntegral.labelsValid) { // off the path too: any critical voxel on the shaft
        const auto& per = mField->perLabel();
        for (int l = 1; l < kMaxLabels; ++l) {
            if (per[std::size_t(l)].critical && mIntegral.labelLengthMm[std::size_t(l)] > 0.0) return true;
        }
    }
    return false;
}

void NeedleForceModel::step(const NeedleInput& in, NeedleOutput& out) noexcept
{
    out.events.clear();
    out.terms = ForceBreakdown{};
    out.fault = out.critical = out.palpating = false;
    out.hubTorque = Vec3d::Zero();
    out.palpation = PalpationOutput{};
    const double t = std::isfinite(in.timeS) ? in.timeS : mLastTimeS;
    const double dt = std::isfinite(in.dtS) && in.dtS > 0.0 ? std::min(in.dtS, mSafety.params().maxDtS) : 0.0;
    const double dirNorm = in.direction.norm();

    // §6.4: a non-finite device reading latches the fault; the force stays zero.
    if (!in.tip.allFinite() || !in.direction.allFinite() || !in.velocity.allFinite() || !std::isfinite(in.timeS) ||
        !(dirNorm > 0.0)) {
        if (!mSafety.faulted()) out.events.push({EventType::Fault, t, mState.tip().depthMm, -1});
        mSafety.latchFault();
    }
    if (mSafety.faulted()) {
        out.force = out.modelForce = Vec3d::Zero();
        out.axialN = out.plungerN = out.limitedN = 0.0;
        out.fault = true;
        return;
    }
    mLastTimeS = t;

    // 1. Kinematics along the path.
    const Vec3d& u = mPath.direction;
    const Vec3d dir = in.direction / dirNorm;
    const Vec3d hub = in.tip - mNeedle.lengthMm * dir;
    // A bending needle (§9): the device holds the hub, the terms read the bent tip.
    NeedleInput bent;
    if (mBeam) {
        mBeam->setRoll(in.rollRad); // a NaN keeps the last roll
        mBeam->update(hub, dir);
        bent = in;
        bent.tip = mBeam->tip();
    }
    const NeedleInput& reading = mBeam ? bent : in;
    const double d = (reading.tip - mPath.origin).dot(u);
    const double v = in.velocity.dot(u);
    if (v > 0.0)
        mLastDirection = 1;
    else if (v < 0.0)
        mLastDirection = -1;
    ForceBreakdown& f = out.terms;

    // Palpation: before the needle touches the skin the tip is
    // felt against the skin map; the needle's layer model takes over at the entry. The
    // mode changes only while neither is in contact (the tip outside the skin on the
    // map and before the first layer on the path), when neither stores any energy, so
    // the hand-over itself can create none (§6.4).
    if (mPalp) {
        const bool needleFree = !mState.skinEntered() && d < mState.surfaceMm();
        if (needleFree && !mPalp->inside(in.tip)) {
            mPalpating = lateralOf(in.tip - mPath.origin, u).norm() > mTerms.palpation.params.entryRadiusMm;
        }
    }
    if (mPalpating) {
        out.palpating = true;
        out.palpation = mPalp->update(in.tip);
        f.palpation = out.palpation.force;
        mProxy.reset();
        mIntegral.reset();
        TipState outside;
        outside.depthMm = d;
        out.tip = outside;
        if (mTerms.lor.on) out.plungerN = mLor.update(0.0, dt);
    } else {
        if (mPalp) mPalp->reset();
        needleTerms(reading, t, dt, d, v, dir, hub, out);
    }
    if (mGuide) f.guidance = mGuide->update(in.tip, t);

    // §1.1 critical structures: zero force and a warning, in this tick (palpation
    // indents the skin, it does not cut: the shaft rule starts with the needle).
    const int current = out.tip.currentLayer();
    const bool critical = !mPalpating && mTerms.critical && touchingCritical();
    if (critical != mCritical) {
        out.events.push({critical ? EventType::CriticalBreach : EventType::CriticalClear, t, d, current});
        mCritical = critical;
    }
    out.axialN = f.elastic + f.proxy + f.viscous + f.damping + f.bone + f.transient + f.keepDirection;
    Vec3d model = -out.axialN * u + f.lateral;
    if (mBeam) { // only here, so that a straight needle's sum keeps its bits
        // §9.5: the beam's hub force reaches the hand through a virtual coupling at the
        // device's stiffness k_c in series with the hub's own K: K·k_c/(K + k_c) is
        // below both, whatever the free span.
        const double kc = mDevice.maxStiffnessNPerMm, kHub = mBeam->hubStiffnessNPerMm();
        const double share = kc > 0.0 ? kc / (kHub + kc) : 0.0;
        f.bending = mPalpating ? Vec3d::Zero() : Vec3d(share * mBeam->hubForce());
        out.hubTorque = mPalpating ? Vec3d::Zero() : mBeam->hubTorque();
        model += f.bending;
    }
    if (mPalp) model += f.palpation;
    if (mGuide) model += f.guidance;
    // §1.1 Eq. 1: F = F_R + F_C + F_G. A critical structure zeroes the tissue's forces;
    // F_G only holds up the handle, so it stays.
    const Vec3d tissue = critical ? Vec3d::Zero() : model;
    f.gravity = mGravity;
    out.modelForce = tissue + mGravity;
    out.critical = critical;
    out.speedMmPerS = v;

    // 4. Safety, on the scaled force (every term alike); F_G passes beside the passivity
    // observer (the handle's weight does the opposite work) but within the device's limits.
    out.force = mSafety.apply(mTerms.renderScale * tissue, hub, dt, mGravity);
    out.limitedN = mSafety.limitedN();
    const bool limited = out.limitedN > 0.0;
    if (limited && !mLimited) out.events.push({EventType::ForceLimited, t, d, current});
    mLimited = limited;
    if (mSafety.faulted()) {
        out.events.push({EventType::Fault, t, d, current});
        out.fault = true;
    }
}

void NeedleForceModel::needleTerms(const NeedleInput& in, double t, double dt, double d, double v, const Vec3d& dir,
    const Vec3d& hub, NeedleOutput& out) noexcept
{
    const Vec3d& u = mPath.direction;

    // 2. Insertion state.
    mState.update(d, t, mNeedle.lengthMm, out.events);
    const TipState& tip = mState.tip();
    const auto& layers = mState.layers();
    bool popped = false;
    for (const Event& e : out.events) {
        if (e.type == EventType::Withdrawn) mProxy.reset(), mPivot.reset(), mLor.reset();
        // The lock ties the needle to its line where cutting starts ([S19], §2.1), not to the
        // planned path: a spring stretched at entry would store energy nobody put in (§1.1).
        if (e.type == EventType::SkinEntry) mLockAnchor = lateralOf(in.tip - mPath.origin, u);
        popped = popped || e.type == EventType::Pop;
        if (mBeam) bendingEvent(e, in.tip, d, dir);
    }
    // Backed off a tenting skin before its puncture: no Withdrawn event, but nothing
    // was cut either.
    if (mBeam && mBeam->entered() && !mState.skinEntered() && d < mState.surfaceMm()) mBeam->withdraw();

    // After skin entry the needle is tied to its line: the profile answers in O(1) (it
    // rebuilds itself, without allocating, if the shaft strays from the line). A bent
    // shaft is integrated along its polyline (§9.5).
    ShaftIntegrator* integ = mLocked && mState.skinEntered() ? mLocked.get() : mIntegrator.get();
    if (integ && (mTerms.damping.on || mTerms.critical)) {
        if (mBeam && mBeam->entered())
            integ->integratePolyline(mBeam->shaft(), mIntegral);
        else
            integ->integrate(Segment{hub, in.tip}, mIntegral);
    }

    // 3. Force terms, axial resistance positive outward.
    ForceBreakdown& f = out.terms;
    double threshold = 0.0; // Coulomb-type terms: the proxy's slip force (§6.2)
    if (mTerms.tip && tip.pushLayer >= 0) f.elastic = layers[std::size_t(tip.pushLayer)].elasticForceN(tip.pushMm);
    const int current = tip.currentLayer();
    threshold += tipSlipForceN(mTerms, tip, layers, v);
    if (mTerms.viscous && current >= 0) f.viscous = tip.viscousNsPerMm * v; // §4 Eq. 3: Σ b_i·l_i·v
    if (mTerms.damping.on && v > 0.0) { // §1.2 Eq. 5, advancing only, chord-weighted
        const DampingSplit split = splitDamping(mTerms.damping, mDevice, mIntegral.dampingIntegral, v);
        f.damping = split.viscousN;
        threshold += split.frictionN;
    }
    if (popped && v > 0.0) mProxy.preload(d, threshold); // the drop at a pop is exact (§3.1 T_f)
    if (current >= 0)
        f.proxy = mProxy.update(d, threshold);
    else
        mProxy.reset();
    if (mTerms.keepDirectionN > 0.0 && v <= 0.0 && tip.inBody)
        f.keepDirection = -mTerms.keepDirectionN * mLastDirection;

    // Bone (§1.3): contact at the device's stiffness; the tip sticks where it met the
    // bone until pulled back; the transient (§2.1 Eq. 2) scales with impact speed.
    Vec3d lateral = Vec3d::Zero();
    const bool onBone = mTerms.bone.on && tip.boneLayer >= 0;
    if (onBone && !mInContact) mContactPoint = in.tip, mContactTimeS = t, mImpactMmPerS = std::max(0.0, v);
    mInContact = onBone;
    if (onBone) {
        const double k = mDevice.maxStiffnessNPerMm;
        f.bone = k * std::max(0.0, tip.penetrationMm);
        lateral -= k * lateralOf(in.tip - mContactPoint, u);
        if (mTerms.bone.transient) f.transient = -mTerms.bone.params.forceN(t - mContactTimeS, mImpactMmPerS);
    }
    // A bending needle's tip node is pinned where it met the bone (§9.5), from the
    // next tick's solve (the beam is solved before the insertion state is known);
    // the tip stops on bone whether its contact force is rendered (§1.3) or the bone
    // is a layer of the force table the tip pushes on ([LP], §4).
    const bool held = tipInBone(tip, layers);
    if (mBeam && held != mBeam->tipPinned()) {
        if (held)
            mBeam->pinTip(in.tip);
        else
            mBeam->releaseTip();
    }
    // Lateral terms after skin entry: the Kelvin pivot correction (§1.4) at the hub,
    // toward the initial line; the trajectory lock ([S19], §6.2) at the tip.
    if (mTerms.pivot.on && mState.skinEntered()) {
        const double theta = std::acos(std::clamp(dir.dot(u), -1.0, 1.0));
        const double fc = mPivot.update(theta, d - mState.surfaceMm(), dt);
        const Vec3d off = lateralOf(hub - mPath.origin, u); // hub's distance from the line
        const Vec3d toward = -lateralOf(off, dir);
        const double n = toward.norm();
        if (n > 1e-12 && fc > 0.0) lateral += (fc / n) * toward;
    }
    if (mTerms.lock.on && mState.skinEntered()) {
        const double k = orDevice(mTerms.lock.stiffnessNPerMm, mDevice.maxStiffnessNPerMm);
        lateral -= k * (lateralOf(in.tip - mPath.origin, u) - mLockAnchor);
    }
    f.lateral = lateral;

    if (mTerms.lor.on)
        out.plungerN = mLor.update(tip.inLayer >= 0 ? layers[std::size_t(tip.inLayer)].lorResistance : 0.0, dt);
    out.tip = tip;
}

void NeedleForceModel::bendingEvent(const Event& e, const Vec3d& tip, double d, const Vec3d& dir) noexcept
{
    // The track starts where the tip first meets the tissue, before a tenting skin is
    // punctured (§9.5): the deflection is made in the first millimetres (§9.2), and
    // a track started at the puncture would hold the tip straight through the tent.
    if (e.type == EventType::SkinContact || (e.type == EventType::SkinEntry && !mBeam->entered())) {
        // The track starts on the skin: back along the shaft from the tip by its depth
        // past the surface (the needle is straight until it touches).
        const double along = dir.dot(mPath.direction);
        const double back = along > 0.1 ? std::max(0.0, d - mState.surfaceMm()) / along : 0.0;
        mBeam->enter(tip - back * dir);
    } else if (e.type == EventType::Withdrawn) {
        mBeam->withdraw();
    }
}

} // namespace voxhap::haptic
