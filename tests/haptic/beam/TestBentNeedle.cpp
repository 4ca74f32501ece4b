// SPDX-License-Identifier: Apache-2.0
/// @file TestBentNeedle.cpp
/// @brief The needle that bends in uniform tissue (physics.md §9, §7 R8): a
/// symmetric tip stays straight; a bevel cuts the constant-curvature arc of the
/// steady state, κ = P/(2·EI·λ); the tip's path converges as the step shrinks and
/// the tissue holds the tip from the first millimetre (each against the rule the
/// model replaced, as the control); a half turn flips the bevel; the shaft follows
/// its track; bone pins the tip; the measured deflections; the needle's section
/// (EI) from its gauge, wall and stylet; the nodes.

#include "core/Errors.h"
#include "core/Math.h"
#include "haptic/beam/BentNeedle.h"
#include "volume/TissueTable.h"

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

namespace voxhap::haptic {
namespace {

/// Inserts a needle along +z from the entry at the origin, the hub pushed along
/// the axis in steps of @p stepMm (1 kHz at 50 mm/s).
struct Insertion {
    BentNeedle needle;
    double hubZ;
    Insertion(const Needle& n, double k, double stepMm = 0.05)
        : needle(BeamParams::fromNeedle(n), std::make_unique<UniformFoundation>(k), Vec3d::UnitX()), hubZ(-n.lengthMm),
          step(stepMm)
    {
        needle.update(Vec3d(0, 0, hubZ), Vec3d::UnitZ());
        needle.enter(Vec3d::Zero());
    }
    /// Push (or pull, negative) the hub by @p mm.
    void advance(double mm)
    {
        const int n = int(std::ceil(std::abs(mm) / step - 1e-9));
        for (int i = 0; i < n; ++i) {
            hubZ += mm / n;
            ASSERT_TRUE(needle.update(Vec3d(0, 0, hubZ), Vec3d::UnitZ()));
        }
    }
    double step;
};

Needle quincke22()
{
    Needle n;
    n.gauge = 22;
    n.tip = TipType::Bevel;
    n.lengthMm = 90.0;
    n.stylet = true;
    return n;
}

/// The rule this model replaced, the control of the tests below: each new track
/// point laid where the shaft lies when the tip passes it (the tissue yields
/// wherever the tip is pushed, as a virtual-spring model's new spring rests at the
/// tip), the uncut tissue ahead resting along the tip's direction of the last
/// solve. One lateral direction, the hub pushed along z by @p stepMm from the
/// entry to @p depthMm in uniform @p k; returns the tip's deflection [mm].
double tipPositionRuleDeflection(const BeamParams& p, double k, double depthMm, double stepMm)
{
    WinklerBeam beam(int(std::lround(p.lengthMm)), p.lengthMm, p.eiNmm2, /*clampedStart=*/true);
    constexpr double kTrackStepMm = 0.25;
    std::vector<double> track{0.0}; // lateral offsets at τ = j·0.25 mm
    double ahead = 0.0;             // the tip's slope of the last solve
    const int n = int(std::ceil(depthMm / stepMm - 1e-9));
    for (int i = 1; i <= n; ++i) {
        const double inserted = depthMm * i / n, from = p.lengthMm - inserted;
        const double end = kTrackStepMm * double(track.size() - 1);
        beam.begin();
        beam.addFoundation(from, [&](double x, double& kk, double& r1, double& r2) {
            const double tau = x - from;
            kk = k, r2 = 0.0;
            if (tau >= end) {
                r1 = track.back() + (tau - end) * ahead;
                return;
            }
            const int j = std::min(int(track.size()) - 2, int(tau / kTrackStepMm));
            const double f = tau / kTrackStepMm - j;
            r1 = track[std::size_t(j)] + f * (track[std::size_t(j + 1)] - track[std::size_t(j)]);
        });
        beam.addEndForce(k * p.bevelFactorMm2, 0.0);
        if (!beam.solve()) return std::nan("");
        ahead = beam.slope(beam.elements(), 0);
        while (kTrackStepMm * double(track.size()) <= inserted) {
            double w1 = 0.0, w2 = 0.0;
            beam.deflectionAt(p.lengthMm - (inserted - kTrackStepMm * double(track.size())), w1, w2);
            track.push_back(w1);
        }
    }
    return beam.deflection(beam.elements(), 0);
}

/// Curvature of the circle through three points [1/mm]: 4·area/(|ab|·|bc|·|ca|).
double curvature(const Vec3d& a, const Vec3d& b, const Vec3d& c)
{
    const double area2 = (b - a).cross(c - a).norm(); // twice the area
    return 2.0 * area2 / ((b - a).norm() * (c - b).norm() * (c - a).norm());
}

TEST(BentNeedle, SymmetricTipInUniformTissueStaysStraight)
{
    Needle n = quincke22();
    n.tip = TipType::Coned; // a pencil point (Whitacre): no lateral force
    Insertion ins(n, 1.0);
    ins.advance(80.0);
    EXPECT_NEAR(ins.needle.insertedMm(), 80.0, 1e-9);
    // No load and a straight track: the solve's right-hand side is zero, so is w.
    EXPECT_EQ(ins.needle.tipDeflectionMm(), 0.0);
    for (int j = 0; j < ins.needle.track().count(); ++j) EXPECT_EQ(ins.needle.track().point(j).head<2>().norm(), 0.0);
    EXPECT_EQ(ins.needle.hubForce().norm(), 0.0);

    // Control: the same needle with a bevel leaves the line by millimetres.
    Insertion bevel(quincke22(), 1.0);
    bevel.advance(80.0);
    EXPECT_GT(bevel.needle.tipDeflectionMm(), 1.0);
}

// The steady state of §9.3, derived for the test: behind the tip the shaft lies
// off the circular track by v(σ) (σ from the tip), EI·v'''' + k·v = 0, decaying
// into the tissue; at the tip no moment (v'' = −κ), the bevel's shear
// (v''' = P/EI), and the tip cutting along its heading, the track's tangent
// (v'(0) = 0). With v = A·e^(−λσ)·(cos λσ + sin λσ): v''(0) = −2Aλ² and
// v'''(0) = 4Aλ³, so κ = P/(2·EI·λ), λ = (k/4EI)^¼.
TEST(BentNeedle, BevelInUniformTissueCutsAnArcOfCurvaturePOver2EILambda)
{
    Needle n;
    n.gauge = 18; // OD 1.270, ID 0.838 mm, no stylet
    n.lengthMm = 150.0;
    n.bevelAngleDeg = 60.0; // a blunt bevel: a gentle arc, slopes below 0.03 rad
    const double k = 1.0;
    const double ei = 193e3 * kPi * (std::pow(1.270, 4) - std::pow(0.838, 4)) / 64.0;
    const double p = k * 1.270 * 1.270 / (2.0 * std::tan(degToRad(60.0)));
    const double lambda = std::pow(k / (4.0 * ei), 0.25);
    const double kappa = p / (2.0 * ei * lambda);

    Insertion ins(n, k);
    ins.advance(140.0);
    EXPECT_NEAR(ins.needle.bevelForce().norm(), p, 1e-12 * p);
    // Past the start-up transient (a few 1/λ = 17 mm) the track is the arc.
    const CutTrack& t = ins.needle.track();
    const auto at = [&](double tau) { return t.point(int(std::lround(tau / t.stepMm()))); };
    // Tolerance: small-slope theory (θ²/2 ≈ 5e-4 at these slopes), the
    // discretisation ((λh)⁴, and the hub's step, O(step²) by the trapezoid rule)
    // and the remaining transient e^(−λ·60 mm) ≈ 3 %: 5 % (0.2 % and 0.3 % when
    // written).
    constexpr double kArcRelative = 0.05;
    EXPECT_NEAR(curvature(at(60.0), at(95.0), at(130.0)), kappa, kArcRelative * kappa);
    EXPECT_NEAR(curvature(at(80.0), at(105.0), at(130.0)), kappa, kArcRelative * kappa);
    // The arc bends toward the bevel's side, +x at orientation 0.
    EXPECT_GT(at(130.0).x(), 0.0);

    // Control: a track laid through the tip's position (v(0) = 0 in place of
    // v'(0) = 0) would be the arc κ = P/(EI·λ), twice as tight.
    EXPECT_GT(std::abs(p / (ei * lambda) - kappa), 10.0 * kArcRelative * kappa);
}

// The tip's path is a property of the needle and the tissue, not of how finely the
// hand's motion is sampled (physics.md §9.3): the 22 G needle pushed 80 mm into
// muscle in hub steps from 1 mm (the planner's) down to 0.05 mm (50 mm/s at
// 1 kHz), against 0.01 mm. The front moves by the trapezoid rule; the tolerance
// asks for at least linear convergence, 0.03 mm of path per mm of step (0.017 mm
// at 1 mm when written, 0.2 % of the 8.9 mm deflection; 0.074 mm at 2 mm, which
// it would refuse).
TEST(BentNeedle, TheTipsPathConvergesAsTheStepShrinks)
{
    const double muscle = volume::TissueTable::builtin().at("muscle").foundationModulus->value;
    constexpr double kPathPerStep = 0.03; // [mm of path per mm of step]
    const auto path = [&](double step) {
        Insertion ins(quincke22(), muscle, step);
        std::vector<Vec3d> tips;
        for (int depth = 10; depth <= 80; depth += 10) {
            ins.advance(10.0);
            tips.push_back(ins.needle.tip());
        }
        return tips;
    };
    const std::vector<Vec3d> fine = path(0.01);
    ASSERT_GT(fine.back().x(), 5.0) << "the needle must bend for the comparison to mean anything";
    for (const double step : {1.0, 0.5, 0.25, 0.1, 0.05}) {
        const std::vector<Vec3d> coarse = path(step);
        double worst = 0.0;
        for (std::size_t i = 0; i < fine.size(); ++i) worst = std::max(worst, (coarse[i] - fine[i]).norm());
        EXPECT_LE(worst, kPathPerStep * step) << "step " << step << " mm";
    }
    // Control: the rule this model replaced (the track laid where the tip is pushed)
    // on the same needle and tissue ends millimetres apart at the two steps (23.2
    // and 29.6 mm when written).
    const BeamParams p = BeamParams::fromNeedle(quincke22());
    const double coarse = tipPositionRuleDeflection(p, muscle, 80.0, 1.0);
    const double fineOld = tipPositionRuleDeflection(p, muscle, 80.0, 0.01);
    EXPECT_GT(std::abs(coarse - fineOld), 100.0 * kPathPerStep * 1.0) << coarse << " against " << fineOld;
}

// Uncut tissue holds the tip from the first millimetre: the bevel presses its face
// into the tissue by at most the diameter D (§9.3), and the tissue it presses on
// holds the tip within about that, whatever the free span between the hub and the
// skin (85–89 mm here). The track, the path cut, has hardly turned yet.
TEST(BentNeedle, TheTissueHoldsTheTipFromTheFirstMillimetre)
{
    const double muscle = volume::TissueTable::builtin().at("muscle").foundationModulus->value;
    const double od = quincke22().outerDiameterMm();
    Insertion ins(quincke22(), muscle, 0.01);
    for (const double depth : {1.0, 2.0, 5.0}) {
        ins.advance(depth - ins.needle.insertedMm());
        EXPECT_LE(ins.needle.tipDeflectionMm(), od) << depth << " mm in";
        EXPECT_LE(ins.needle.track().front().head<2>().norm(), 0.2 * od) << depth << " mm in";
    }
    // Control: the rule this model replaced lets the long free span swing the tip
    // millimetres off the line 5 mm in (4.2 mm when written).
    EXPECT_GT(tipPositionRuleDeflection(BeamParams::fromNeedle(quincke22()), muscle, 5.0, 0.01), 3.0 * od);
}

TEST(BentNeedle, AHalfTurnFlipsTheBevelAndSteersBack)
{
    const double gel = volume::TissueTable::builtin().at("muscle").foundationModulus->value; // fitted on gel (§9.2)
    Insertion straightOn(quincke22(), gel), turned(quincke22(), gel);
    straightOn.advance(40.0);
    turned.advance(40.0);
    turned.needle.setRoll(kPi); // the clinician's half turn
    straightOn.advance(40.0);
    turned.advance(40.0);
    EXPECT_NEAR(turned.needle.bevelForce().x(), -straightOn.needle.bevelForce().x(), 1e-12);
    EXPECT_GT(straightOn.needle.bevelForce().x(), 0.0);
    // Without the turn the tip keeps leaving the line toward +x; with it, it ends
    // nearer the line (8.9 and 4.4 mm when written).
    EXPECT_GT(straightOn.needle.tip().x(), 4.0);
    EXPECT_LT(turned.needle.tip().x(), straightOn.needle.tip().x() - 1.0);
    // Over the second half the track curves toward −x after the turn (its midpoint
    // lies beyond the chord toward +x), toward +x without it (control).
    const auto bow = [](const CutTrack& t) {
        const auto at = [&](double tau) { return t.point(int(std::lround(tau / t.stepMm()))); };
        return at(60.0).x() - 0.5 * (at(45.0).x() + at(75.0).x());
    };
    EXPECT_GT(bow(turned.needle.track()), 0.0);
    EXPECT_LT(bow(straightOn.needle.track()), 0.0);
}

TEST(BentNeedle, TheShaftFollowsItsTrackAndTheBevelLetsGoOnRetraction)
{
    Insertion ins(quincke22(), 1.0);
    ins.advance(60.0);
    const int cut = ins.needle.track().count();
    const double front = ins.needle.track().frontMm();
    const double bevelLength = 0.718 / std::tan(degToRad(20.0));
    ins.advance(-0.5 * bevelLength);
    EXPECT_EQ(ins.needle.track().count(), cut) << "retracting cuts nothing";
    EXPECT_EQ(ins.needle.track().frontMm(), front);
    // The face backed half out of its cut: half of P = k·D·(D·cot α)/2.
    const double back = ins.needle.track().frontMm() - ins.needle.insertedMm();
    EXPECT_NEAR(back, 0.5 * bevelLength, 1e-9);
    EXPECT_NEAR(ins.needle.bevelForce().norm(), 0.5 * 1.0 * 0.718 * bevelLength / 2.0, 1e-9);
    ins.advance(-20.0);
    EXPECT_EQ(ins.needle.bevelForce().norm(), 0.0);
    // Unloaded, the inserted shaft lies on its track (the tip at arc length 40 mm on
    // it), but for its free end, which holds no moment and so does not follow the
    // track's curvature κ: it lies off by κ/(2λ²) (a semi-infinite beam under the
    // end moment EI·κ, Hetényi), κ the track's over its last 10 mm.
    const CutTrack& t = ins.needle.track();
    const double tau = ins.needle.insertedMm();
    Vec3d onTrack, back1, back2;
    double k = 0.0;
    t.sample(tau, onTrack, k);
    t.sample(tau - 5.0, back1, k);
    t.sample(tau - 10.0, back2, k);
    const double lambda = std::pow(1.0 / (4.0 * quincke22().bendingStiffnessNmm2()), 0.25);
    const double straightening = curvature(back2, back1, onTrack) / (2.0 * lambda * lambda);
    // Tolerance: the curvature is not constant over the 1/λ = 10 mm the end reads,
    // and the clamp's bending near the skin reaches the tip as e^(−4) ≈ 2 %: 20 %.
    EXPECT_NEAR((ins.needle.tip() - onTrack).norm(), straightening, 0.2 * straightening);
    // Control: the straight line the hub points along is far from it.
    EXPECT_GT(onTrack.head<2>().norm(), 10.0 * straightening);
}

// Bone pins the beam's tip node (physics.md §9.5): a hand that moves the hub
// sideways bends the shaft between the hub and the held tip, the bevel presses on
// nothing and nothing is cut. Controls: a free tip 3 mm in moves when the hub does
// (the shaft levers it about the tissue, 0.045 mm against the hub's 2 mm when
// written), and a free needle pushed on cuts.
TEST(BentNeedle, BonePinsTheTip)
{
    const double muscle = volume::TissueTable::builtin().at("muscle").foundationModulus->value;
    Insertion pinned(quincke22(), muscle), loose(quincke22(), muscle);
    pinned.advance(3.0);
    loose.advance(3.0);
    const Vec3d at = pinned.needle.tip();
    const int cut = pinned.needle.track().count();
    pinned.needle.pinTip(at);
    ASSERT_TRUE(pinned.needle.tipPinned());
    constexpr double kSideMm = 2.0;
    for (Insertion* ins : {&pinned, &loose}) {
        ASSERT_TRUE(ins->needle.update(Vec3d(kSideMm, 0.0, ins->hubZ), Vec3d::UnitZ()));
    }
    // The pin is exact (the unknown is eliminated): the tip is where bone holds it
    // across the shaft, to round-off.
    const Vec3d held = pinned.needle.tip() - at;
    EXPECT_NEAR((held - held.dot(Vec3d::UnitZ()) * Vec3d::UnitZ()).norm(), 0.0, 1e-9);
    EXPECT_EQ(pinned.needle.bevelForce().norm(), 0.0);
    const Vec3d moved = loose.needle.tip() - at;
    EXPECT_GT((moved - moved.dot(Vec3d::UnitZ()) * Vec3d::UnitZ()).norm(), 0.01) << "control: a free tip moves";
    // Pushed on against the bone, the pinned needle cuts nothing.
    for (Insertion* ins : {&pinned, &loose}) {
        for (int i = 0; i < 20; ++i) ins->needle.update(Vec3d(kSideMm, 0.0, ins->hubZ += 0.05), Vec3d::UnitZ());
    }
    EXPECT_EQ(pinned.needle.track().count(), cut);
    EXPECT_GT(loose.needle.track().count(), cut) << "control: a free needle cuts on";
    // Released, the bevel presses again.
    pinned.needle.releaseTip();
    ASSERT_TRUE(pinned.needle.update(Vec3d(kSideMm, 0.0, pinned.hubZ), Vec3d::UnitZ()));
    EXPECT_GT(pinned.needle.bevelForce().norm(), 0.0);
}

TEST(BentNeedle, SectionFromGaugeWallAndStylet)
{
    Needle n = quincke22();
    n.stylet = false;
    // ISO 9626 regular wall, 22 G: 0.7176 / 0.413 mm; AISI 304 at 193 GPa.
    EXPECT_DOUBLE_EQ(n.bendingStiffnessNmm2(), 193e3 * kPi * (std::pow(0.718, 4) - std::pow(0.413, 4)) / 64.0);
    n.stylet = true; // a stylet filling the lumen makes the pair a solid rod
    EXPECT_DOUBLE_EQ(n.bendingStiffnessNmm2(), 193e3 * kPi * std::pow(0.718, 4) / 64.0);
    n.stylet = false;
    n.innerDiameterGivenMm = 0.5;
    n.material = NeedleMaterial::Nitinol;
    EXPECT_DOUBLE_EQ(n.bendingStiffnessNmm2(), 75e3 * kPi * (std::pow(0.718, 4) - std::pow(0.5, 4)) / 64.0);

    const auto refused = [](Needle bad, const char* key) {
        try {
            (void)BeamParams::fromNeedle(bad);
        } catch (const ValueError& e) {
            return std::string(e.what()).find(key) != std::string::npos;
        }
        return false;
    };
    Needle bad = quincke22();
    bad.innerDiameterGivenMm = 0.718; // the OD
    EXPECT_TRUE(refused(bad, "needle.inner_diameter_mm"));
    bad.innerDiameterGivenMm = 0.717;
    EXPECT_FALSE(refused(bad, "needle.inner_diameter_mm")) << "control: a thin wall is a wall";
    bad = quincke22();
    for (const double a : {0.0, 90.0, -5.0, 120.0}) {
        bad.bevelAngleDeg = a;
        EXPECT_TRUE(refused(bad, "needle.bevel_angle_deg")) << a;
    }
}

// The measured deflections of physics.md §9.2. Rand et al. 2016: a 22 G Quincke
// needle 8.89 ± 0.17 mm off its line at 80 mm in ballistic gel. The table's muscle
// modulus was fitted on that datum (gel is the muscle simulant), so that case only
// pins the fit: within the measurement's standard deviation. The checks are the
// data not fitted: Rand's 25 G Quincke deflected more than the 22 G at 80 mm
// (12.0 mm when written; the rule this model replaced had it less); Drummond &
// Scott 1980, 22 and 25 G Quincke needles (8.9 cm) through beef, "about 1 mm for
// each centimetre" of travel, against the model's deflection per centimetre at
// 40–60 mm (22 G 0.69–0.90, 25 G 0.95–1.23 mm/cm when written): within 35 %, one
// rounded figure for both gauges, and beef is not the gel k was fitted on.
TEST(BentNeedle, MeasuredDeflectionsInGelAndBeef)
{
    const double muscle = volume::TissueTable::builtin().at("muscle").foundationModulus->value;
    const auto deflection = [muscle](int gauge, double length, double depth) {
        Needle n = quincke22();
        n.gauge = gauge;
        n.lengthMm = length;
        Insertion ins(n, muscle);
        ins.advance(depth);
        return ins.needle.tipDeflectionMm();
    };
    const double rand22 = deflection(22, 90.0, 80.0);
    EXPECT_NEAR(rand22, 8.89, 0.17) << "the fitted datum (Rand 2016)";
    EXPECT_GT(deflection(25, 90.0, 80.0), rand22) << "Rand 2016: the thinner needle deflects more";
    constexpr double kDrummondRelative = 0.35;
    for (const int gauge : {22, 25}) {
        for (const double depth : {40.0, 50.0, 60.0}) {
            const double slope = deflection(gauge, 89.0, depth) / (depth / 10.0);
            EXPECT_NEAR(slope, 1.0, kDrummondRelative) << gauge << " G at " << depth << " mm [mm/cm]";
        }
    }
    // Control: at 10 mm, before the track has curved, the model's deflection per
    // centimetre is far below Drummond's (0.41 mm/cm for 22 G): the comparison can fail.
    EXPECT_LT(deflection(22, 89.0, 10.0) / 1.0, 1.0 - kDrummondRelative);
}

TEST(BentNeedle, AtLeastAMillimetreOfNeedlePerNodeAndAtMost150Nodes)
{
    const auto nodes = [](double length) {
        Needle n = quincke22();
        n.lengthMm = length;
        return BentNeedle(BeamParams::fromNeedle(n), std::make_unique<UniformFoundation>(1.0), Vec3d::UnitX()).nodes();
    };
    EXPECT_EQ(nodes(90.0), 91);
    EXPECT_EQ(nodes(90.7), 91);
    EXPECT_EQ(nodes(149.0), 150);
    EXPECT_EQ(nodes(300.0), 150);
    EXPECT_EQ(nodes(0.4), 2);
}

} // namespace
} // namespace voxhap::haptic
