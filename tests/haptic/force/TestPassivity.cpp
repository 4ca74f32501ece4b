// SPDX-License-Identifier: Apache-2.0
/// @file TestPassivity.cpp
/// @brief Passivity of the force models themselves (physics.md §1.1 rule, §6.1,
/// §6.4), every built-in scene, with the passivity controller off; and how much
/// the controller (§6.2 guard) changes the force when it is on.

#include "common/BuiltinTable.h"
#include "common/SceneCache.h"

#include "haptic/force/NeedleForceModel.h"
#include "haptic/force/Safety.h"
#include "haptic/scene/Scene.h"

#include <Eigen/Geometry> // for cross and unitOrthogonal
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <string>

namespace voxhap::haptic::passivity {
namespace {

using voxhap::test::table;

const SceneInstance& instance(const std::string& name) { return test::sceneInstance(name); }

/// The stiffest spring the model can present at the hub [N/mm]: the device's
/// maximum stiffness (stick-slip proxy, bone contact, trajectory lock: §1.3,
/// §6.2), the steepest elastic stage of a layer up to its puncture (§2.1 Eq. 4,
/// §3.1, §4 Eq. 2), and for the Kelvin pivot (§1.4) its instantaneous stiffness
/// seen at the hub, (κ1 + κ2)·D³/(3·L_h·L_hub) with D the inserted depth and
/// L_hub = needle length − D the pivot-to-hub lever.
double stiffestSpringNPerMm(const SceneInstance& inst, double maxDepthMm)
{
    const auto& terms = inst.scene().terms;
    const DeviceLimits& dev = inst.scene().device;
    double k = dev.maxStiffnessNPerMm;
    if (terms.couplingNPerMm > 0.0) k = std::max(k, terms.couplingNPerMm);
    if (terms.lock.on && terms.lock.stiffnessNPerMm > 0.0) k = std::max(k, terms.lock.stiffnessNPerMm);
    for (const Layer& l : inst.layers()) {
        if (!l.tents) continue;
        // Slope c1 + 2·c2·z + 3·c3·z² over the elastic stage, z from 0 to the pop.
        for (double z = 0.0; z <= std::min(l.punctureDepthMm, 200.0); z += 1e-3) {
            const double slope = l.elastic[1] + z * (2.0 * l.elastic[2] + 3.0 * z * l.elastic[3]);
            k = std::max(k, std::abs(slope));
            if (l.elasticForceN(z) >= l.punctureForceN) break;
        }
    }
    if (terms.pivot.on) {
        const PivotParams& p = terms.pivot.params;
        const double d = maxDepthMm, lever = std::max(inst.scene().needle.lengthMm - d, 1.0);
        k = std::max(k, (p.kappa1NPerMm2 + p.kappa2NPerMm2) * d * d * d / (3.0 * p.hubDistanceMm * lever));
    }
    return k;
}

/// The largest virtual damping [N·s/mm]: the device's rendered share of Kyung's
/// voxel damping (§6.2) and [LP]'s shaft friction Σ b_i·l_i over the whole needle (§4 Eq. 3).
double largestDampingNsPerMm(const SceneInstance& inst)
{
    double b = inst.scene().terms.damping.on ? inst.scene().device.maxDampingNsPerMm : 0.0;
    if (inst.scene().terms.viscous) {
        double bMax = 0.0;
        for (const Layer& l : inst.layers()) bMax = std::max(bMax, l.viscousNsPerMm2);
        b += bMax * inst.scene().needle.lengthMm;
    }
    return b;
}

/// Drives one model along a trajectory of the tip at the servo rate and books the
/// work done on the hand, Σ F_n·(x_{n+1} − x_n) with x the hub (the point the
/// hand holds and the observer of Safety.h watches; zero-order hold, the
/// sampled-data truth), for three forces:
/// - the model's force before any safety stage;
/// - that force through a Safety with the passivity controller off (the clamps only);
/// - the rendered force, controller on (the model's own safety stage).
/// It also accumulates the bound the model must meet (see leakNmm below). The
/// bending scenes' hub force reaches the hand through a coupling no stiffer than
/// the device (§9.5), so the device's maximum stiffness bounds it too.
class Meter {
public:
    Meter(const SceneInstance& inst, double maxDepthMm)
        : mInst(inst), mModel(inst.makeModel()), mOff(offParams(*mModel)), mDt(1.0 / inst.scene().rateHz),
          mK(stiffestSpringNPerMm(inst, maxDepthMm)), mB(largestDampingNsPerMm(inst))
    {
    }
    static SafetyParams offParams(const NeedleForceModel& m)
    {
        SafetyParams p = SafetyParams::fromDevice(m.device());
        p.passivity = false;
        return p;
    }

    void move(const Vec3d& tip, const Vec3d& dir)
    {
        const Vec3d hub = tip - mModel->needle().lengthMm * dir;
        if (mHave) {
            const Vec3d dx = hub - mLastHub;
            mModelNmm += mModelF.dot(dx);
            mOffNmm += mOffF.dot(dx);
            mOnNmm += mOnF.dot(dx);
            // The sampled-data leak (Colgate & Schenkel, §6.1). A spring force F(x) with
            // |F'| <= K, held from the tick's start over the step Δ, does work
            // F(x_n)·Δ = ∫F dx + ∫(F(x_n) − F(x)) dx <= ∫F dx + K·Δ²/2; round a closed
            // loop ∫F dx is 0 for the conservative part and negative for the rest
            // (slip, pops, cutting). A damper B on the backward-difference velocity
            // does −B·Δ_{n−1}·Δ_n/T <= B·(Δ_{n−1}² + Δ_n²)/(2T), summed <= B·ΣΔ²/T.
            // Their condition b > K·T/2 + |B| is the device damping that absorbs
            // exactly this; the model may leak no more. Anything above it is energy
            // the model creates.
            mLeakNmm += (0.5 * mK + mB / mDt) * dx.squaredNorm();
            // The bone transient (§2.1 Eq. 2) is an active display by design: a
            // decaying sine of at most its clamp, for its duration after each contact.
            if (mInst.scene().terms.bone.transient && mTransientUntil >= mT)
                mActiveNmm += mInst.scene().terms.bone.params.peakClampN * dx.norm();
            // [LP]'s f_keepdir (§4 Eq. 1) is device compensation, active by design: a
            // constant force along the last motion, at most keepDirectionN·|Δx| a tick.
            mActiveNmm += mInst.scene().terms.keepDirectionN * dx.norm();
            // A bending needle's bevel force (§9.5) is a follower load, active by design:
            // it does at most |P|·|Δx| a tick on the shaft that moves with the hand.
            mActiveNmm += mBevelN * dx.norm();
        }
        NeedleInput in;
        in.timeS = mT;
        in.dtS = mDt;
        in.tip = tip;
        in.direction = dir;
        in.velocity = mHave ? Vec3d((tip - mLastTip) / mDt) : Vec3d::Zero();
        mModel->step(in, mOut);
        for (const Event& e : mOut.events) {
            if (e.type == EventType::BoneContact)
                mTransientUntil = mT + mInst.scene().terms.bone.params.durationS + mDt;
        }
        mModelF = mOut.modelForce;
        mBevelN = mModel->bentNeedle() ? mModel->bentNeedle()->bevelForce().norm() : 0.0;
        // The same stages the model renders through: the scene's force scale on the
        // tissue's force, F_G beside the observer (NeedleForceModel step 4).
        const Vec3d g = mOut.terms.gravity;
        mOffF = mOff.apply(mInst.scene().terms.renderScale * (mOut.modelForce - g), hub, mDt, g);
        mOnF = mOut.force;
        // While the model's own running energy has stayed at or below zero the observer
        // has nothing to take back, so the controller must leave the force alone.
        mSilent = mSilent && mOffNmm <= 0.0;
        if (mSilent) mMaxSilentChange = std::max(mMaxSilentChange, (mOnF - mOffF).norm());
        mMaxChange = std::max(mMaxChange, (mOnF - mOffF).norm());
        mLastHub = hub;
        mLastTip = tip;
        mHave = true;
        mT += mDt;
    }

    double modelNmm() const { return mModelNmm; }
    double offNmm() const { return mOffNmm; }
    double onNmm() const { return mOnNmm; }
    double leakNmm() const { return mLeakNmm; }
    double activeNmm() const { return mActiveNmm; }
    double maxChange() const { return mMaxChange; }
    double maxSilentChange() const { return mMaxSilentChange; }
    const NeedleOutput& out() const { return mOut; }

private:
    const SceneInstance& mInst;
    std::unique_ptr<NeedleForceModel> mModel;
    Safety mOff;
    double mDt, mK, mB, mT = 0.0;
    double mModelNmm = 0, mOffNmm = 0, mOnNmm = 0, mLeakNmm = 0, mActiveNmm = 0;
    double mMaxChange = 0, mMaxSilentChange = 0;
    double mTransientUntil = -1.0;
    double mBevelN = 0.0; ///< the bevel's force this tick [N] (bending scenes)
    bool mHave = false, mSilent = true;
    Vec3d mModelF = Vec3d::Zero(), mOffF = Vec3d::Zero(), mOnF = Vec3d::Zero();
    Vec3d mLastHub = Vec3d::Zero(), mLastTip = Vec3d::Zero();
    NeedleOutput mOut;
};

/// Round-off of Σ F·Δx over ~10⁵ ticks of forces up to 20 N and steps up to 0.2 mm:
/// 1e-16 relative per product, summed, stays below 1e-9 N·mm.
constexpr double kRoundOffNmm = 1e-9;
/// §6.4: with the controller on, a closed loop delivers at most 1e-6 J = 1e-3 N·mm.
constexpr double kPassivityNmm = 1e-3;

/// How far the rendered force may differ from the model's while the controller is
/// silent: the model's hub (tip − L·direction/|direction|) and the meter's differ by
/// round-off, ~1e-16 N·mm in the observer's sum, spread over steps of ≥ 1e-4 mm.
constexpr double kSilentN = 1e-9;

/// The checks of one closed trajectory (it ends where it started, out of the body,
/// so no energy is stored at either end and the whole budget is the leak bound).
void expectPassive(const Meter& m, const std::string& what)
{
    SCOPED_TRACE(what);
    const double bound = m.leakNmm() + m.activeNmm() + kRoundOffNmm;
    // Controller off. The model alone, before any safety stage: it may leak no more
    // than a sampled spring and damper of its stiffest terms (§6.1), plus the terms
    // that are active by design.
    EXPECT_LE(m.modelNmm(), bound) << "leak bound " << m.leakNmm() << ", active terms " << m.activeNmm();
    // The same through the device limits (Safety with passivity = false).
    EXPECT_LE(m.offNmm(), bound) << "leak bound " << m.leakNmm() << ", active terms " << m.activeNmm();
    // Controller on: §6.4's criterion on what the hand receives...
    EXPECT_LE(m.onNmm(), kPassivityNmm);
    // ...and how much the controller changes: it only takes energy out (the rendered
    // stream does no more work than the clamped model's), never more than the model
    // could have leaked, and not at all while the model's running energy is ≤ 0.
    EXPECT_LE(m.onNmm(), m.offNmm() + kRoundOffNmm);
    EXPECT_LE(m.offNmm() - m.onNmm(), bound);
    EXPECT_LE(m.maxSilentChange(), kSilentN);
}

double fullDepth(const SceneInstance& inst)
{
    return inst.scene().depthMm ? *inst.scene().depthMm : (inst.target() - inst.entry()).norm();
}

class Passivity : public testing::TestWithParam<std::string> { };

TEST_P(Passivity, InsertRetractLoops)
{
    const SceneInstance& inst = instance(GetParam());
    const Vec3d e = inst.entry(), u = (inst.target() - inst.entry()).normalized();
    const double full = fullDepth(inst) + 5.0;
    for (const double depth : {3.0, 9.9, 0.5 * full, full}) {
        for (const double speed : {5.0, 50.0, 200.0}) {
            Meter m(inst, full);
            const double step = speed / inst.scene().rateHz;
            for (int loop = 0; loop < 2; ++loop) {
                for (double d = -5.0; d < depth; d += step) m.move(e + d * u, u);
                for (double d = depth; d > -5.0; d -= step) m.move(e + d * u, u);
            }
            m.move(e - 5.0 * u, u);
            expectPassive(m, GetParam() + " depth " + std::to_string(depth) + " speed " + std::to_string(speed));
        }
    }
}

TEST_P(Passivity, RandomAxialWalkReturningHome)
{
    const SceneInstance& inst = instance(GetParam());
    const Vec3d e = inst.entry(), u = (inst.target() - inst.entry()).normalized();
    const double full = fullDepth(inst) + 5.0;
    std::mt19937 rng(7);
    std::normal_distribution<double> g(0.0, 1.0);
    Meter m(inst, full);
    double d = -5.0;
    for (int i = 0; i < 60000; ++i) {
        d = std::clamp(d + 0.02 * g(rng) + 0.001, -5.0, full);
        m.move(e + d * u, u);
    }
    for (; d > -5.0; d -= 0.02) m.move(e + d * u, u);
    m.move(e - 5.0 * u, u);
    expectPassive(m, GetParam() + " walk");
}

TEST_P(Passivity, LateralCirclesAndSquaresAfterSkinEntry)
{
    const SceneInstance& inst = instance(GetParam());
    const Vec3d e = inst.entry(), u = (inst.target() - inst.entry()).normalized();
    const Vec3d a = u.unitOrthogonal(), b = u.cross(a);
    const double depth = std::min(25.0, 0.5 * fullDepth(inst));
    Meter m(inst, depth);
    for (double d = -5.0; d < depth; d += 0.01) m.move(e + d * u, u);
    const double tilt = 5.0 * kPi / 180.0;
    for (int i = 0; i <= 3000; ++i) {
        const double phi = 2.0 * kPi * i / 1000.0;
        const double th = tilt * std::min(1.0, std::min(i, 3000 - i) / 100.0);
        const Vec3d dir = (std::cos(th) * u + std::sin(th) * (std::cos(phi) * a + std::sin(phi) * b)).normalized();
        m.move(e + depth * dir, dir);
        // R7 in the pipeline: the Kelvin correction stays within [K01]'s 2 N (§1.4); at
        // this depth no bone is met, so it is the only lateral term.
        if (inst.scene().terms.pivot.on && !inst.scene().terms.lock.on) {
            EXPECT_LE(m.out().terms.lateral.norm(), inst.scene().terms.pivot.params.maxForceN + 1e-12);
        }
    }
    const Vec3d c = e + depth * u;
    for (int i = 0; i <= 4000; ++i) {
        const double s = (i % 1000) / 1000.0 * 2.0;
        const int side = i / 1000 % 4;
        const Vec3d corner[4] = {Vec3d::Zero(), 2.0 * a, 2.0 * (a + b), 2.0 * b};
        const Vec3d off = corner[side] + 0.5 * s * (corner[(side + 1) % 4] - corner[side]);
        m.move(c + off, u);
    }
    for (double d = depth; d > -5.0; d -= 0.01) m.move(e + d * u, u);
    expectPassive(m, GetParam() + " circles");
}

// A random walk of the tip in three dimensions, the needle kept parallel to the path:
// the trajectory lock and the bone's lateral stick see sideways motion at every depth.
// (Rotations are the circles above, about the skin pivot: a rotation about another
// point moves the tip, where the lock and the bone act, without moving the hub, where
// a 3-DoF device renders and the work is booked: work no device does.)
TEST_P(Passivity, RandomWalkInThreeDimensions)
{
    const SceneInstance& inst = instance(GetParam());
    const Vec3d e = inst.entry(), u = (inst.target() - inst.entry()).normalized();
    const Vec3d a = u.unitOrthogonal(), b = u.cross(a);
    const double full = fullDepth(inst) + 5.0;
    std::mt19937 rng(11);
    std::normal_distribution<double> g(0.0, 1.0);
    Meter m(inst, full);
    Vec3d tip = e - 5.0 * u;
    for (int i = 0; i < 60000; ++i) {
        tip += 0.02 * g(rng) * u + 0.005 * (g(rng) * a + g(rng) * b) + 0.001 * u;
        const Vec3d lat = tip - e - (tip - e).dot(u) * u;
        if (lat.norm() > 1.0) tip -= 0.01 * lat; // stay near the line
        tip += std::clamp((tip - e).dot(u), -5.0, full) * u - (tip - e).dot(u) * u;
        m.move(tip, u);
    }
    // Back out along a straight line to the start.
    const Vec3d home = e - 5.0 * u, t0 = tip;
    const int n = int((tip - home).norm() / 0.02) + 1;
    for (int i = 1; i <= n; ++i) m.move(t0 + (double(i) / n) * (home - t0), u);
    expectPassive(m, GetParam() + " walk3d");
}

// Entering the skin beside the path and coming back onto it: the lock (§2.1, §6.2)
// may not hand back energy that was never put in.
TEST_P(Passivity, SkinEntryBesideThePath)
{
    const SceneInstance& inst = instance(GetParam());
    const Vec3d e = inst.entry(), u = (inst.target() - inst.entry()).normalized();
    const Vec3d side = 0.5 * u.unitOrthogonal(); // 0.5 mm beside the path
    const double depth = std::min(15.0, 0.5 * fullDepth(inst));
    Meter m(inst, depth);
    for (double d = -5.0; d < depth; d += 0.005) m.move(e + side + d * u, u);
    // Sideways onto the path at constant depth: no axial motion, so no cutting or
    // viscous work. The lock stored nothing at entry (its line is where the needle
    // entered), so this leg may return no more than its own sampling leak.
    const double w0 = m.modelNmm(), leak0 = m.leakNmm();
    for (double s = 1.0; s > 0.0; s -= 0.001) m.move(e + s * side + depth * u, u); // onto the path
    EXPECT_LE(m.modelNmm() - w0, m.leakNmm() - leak0 + kRoundOffNmm) << "energy stored by the lock at skin entry";
    for (double d = depth; d > -5.0; d -= 0.005) m.move(e + d * u, u);
    for (double s = 0.0; s <= 1.0; s += 0.001) m.move(e + s * side - 5.0 * u, u); // back outside
    expectPassive(m, GetParam() + " beside");
}

INSTANTIATE_TEST_SUITE_P(
    Scenes, Passivity, testing::ValuesIn(builtinSceneNames()), [](const testing::TestParamInfo<std::string>& i) {
        std::string s = i.param;
        std::replace(s.begin(), s.end(), '-', '_');
        return s;
    });

} // namespace
} // namespace voxhap::haptic::passivity
