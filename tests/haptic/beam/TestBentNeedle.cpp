// SPDX-License-Identifier: Apache-2.0
/// @file TestBentNeedle.cpp
/// @brief The needle that bends in uniform tissue (physics.md §9, §7 R8): a
/// symmetric tip stays straight; a bevel cuts the constant-curvature arc of the
/// steady state, κ = P/(EI·λ); a half turn flips it; the shaft follows its
/// track; the needle's section (EI) from its gauge, wall and stylet; the nodes.

#include "haptic/beam/BentNeedle.h"
#include "core/Errors.h"
#include "core/Math.h"
#include "volume/TissueTable.h"

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

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
        const int n = int(std::ceil(std::abs(mm) / step));
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
// off the circular track by v(σ), EI·v'''' + k·v = 0, decaying into the tissue;
// at the tip no moment (v'' = −κ), the bevel's shear (v''' = P/EI) and the tip on
// its own track (v(0) = 0). With v = B·e^(−λσ)·sin λσ: v''' (0) = 2Bλ³ and
// v''(0) = −2Bλ², so κ = P/(EI·λ), λ = (k/4EI)^¼.
TEST(BentNeedle, BevelInUniformTissueCutsAnArcOfCurvaturePOverEILambda)
{
    Needle n;
    n.gauge = 18; // OD 1.270, ID 0.838 mm, no stylet
    n.lengthMm = 150.0;
    n.bevelAngleDeg = 60.0; // a blunt bevel: a gentle arc, slopes below 0.07 rad
    const double k = 1.0;
    const double ei = 193e3 * kPi * (std::pow(1.270, 4) - std::pow(0.838, 4)) / 64.0;
    const double p = k * 1.270 * 1.270 / (2.0 * std::tan(degToRad(60.0)));
    const double lambda = std::pow(k / (4.0 * ei), 0.25);
    const double kappa = p / (ei * lambda);

    Insertion ins(n, k);
    ins.advance(140.0);
    EXPECT_NEAR(ins.needle.bevelForce().norm(), p, 1e-12 * p);
    // Past the start-up transient (a few 1/λ = 17 mm) the track is the arc.
    const CutTrack& t = ins.needle.track();
    const auto at = [&](double tau) { return t.point(int(std::lround(tau / t.stepMm()))); };
    // Tolerance: small-slope theory (θ²/2 ≈ 2e-3 at these slopes), the
    // discretisation ((λh)⁴ and a track step of λ·0.25 mm ≈ 1.5 % of a decay
    // length) and the remaining transient e^(−λ·60 mm) ≈ 3 %: 6 %.
    constexpr double kArcRelative = 0.06;
    EXPECT_NEAR(curvature(at(60.0), at(95.0), at(130.0)), kappa, kArcRelative * kappa);
    EXPECT_NEAR(curvature(at(80.0), at(105.0), at(130.0)), kappa, kArcRelative * kappa);
    // The arc bends toward the bevel's side, +x at orientation 0.
    EXPECT_GT(at(130.0).x(), 0.0);

    // Control: the kinematic limit of a beam without a foundation's decay (the
    // cantilever curvature P·L/EI at the same depth) is a different arc.
    EXPECT_GT(std::abs(p * 140.0 / ei - kappa), kArcRelative * kappa);
}

TEST(BentNeedle, AHalfTurnFlipsTheBevelAndSteersBack)
{
    const double gel = 0.1; // about ballistic gel's fitted modulus (physics.md §9.2)
    Insertion straightOn(quincke22(), gel), turned(quincke22(), gel);
    straightOn.advance(40.0);
    turned.advance(40.0);
    turned.needle.setRoll(kPi); // the clinician's half turn
    straightOn.advance(40.0);
    turned.advance(40.0);
    EXPECT_NEAR(turned.needle.bevelForce().x(), -straightOn.needle.bevelForce().x(), 1e-12);
    EXPECT_GT(straightOn.needle.bevelForce().x(), 0.0);
    // Without the turn the tip keeps leaving the line toward +x; with it, it ends
    // nearer the line (8.8 and 7.1 mm when written).
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
    const double bevelLength = 0.718 / std::tan(degToRad(20.0));
    ins.advance(-0.5 * bevelLength);
    EXPECT_EQ(ins.needle.track().count(), cut) << "retracting cuts nothing";
    // The face backed about half out of its cut (the track ends within a step of
    // where the tip stopped): that share of P = k·D·(D·cot α)/2.
    const double back = ins.needle.track().lengthMm() - ins.needle.insertedMm();
    EXPECT_GT(back, 0.5 * bevelLength - 0.25 - 1e-9);
    EXPECT_LE(back, 0.5 * bevelLength + 1e-9);
    EXPECT_NEAR(ins.needle.bevelForce().norm(), (1.0 - back / bevelLength) * 1.0 * 0.718 * bevelLength / 2.0, 1e-9);
    ins.advance(-20.0);
    EXPECT_EQ(ins.needle.bevelForce().norm(), 0.0);
    // Unloaded, the inserted shaft lies on its track (the tip at arc length 40 mm on it).
    const CutTrack& t = ins.needle.track();
    const double tau = ins.needle.insertedMm();
    Vec3d onTrack;
    double k = 0.0;
    t.sample(tau, Vec3d::UnitZ(), onTrack, k);
    // The clamp bends the shaft near the skin toward the hub's axis; at the tip,
    // 40 mm ≈ 4/λ in, that reaches e^(−4)·(the track's offset) ≈ 2 % of it.
    EXPECT_NEAR((ins.needle.tip() - onTrack).norm(), 0.0, 0.03 * onTrack.head<2>().norm() + 1e-3);
    // Control: the straight line the hub points along is far from it.
    EXPECT_GT(onTrack.head<2>().norm(), 0.5);
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
// pins the fit: within the measurement's standard deviation. The check is the data
// not fitted: Drummond & Scott 1980, 22 and 25 G Quincke needles (8.9 cm) through
// beef, "about 1 mm for each centimetre" of travel, against the slope the model
// gives past 40 mm (1.26 and 0.95 mm/cm when written): within 30 %.
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
    EXPECT_NEAR(deflection(22, 90.0, 80.0), 8.89, 0.17) << "the fitted datum (Rand 2016)";
    constexpr double kDrummondRelative = 0.3; // the deviation reported in physics.md §9.2, with room
    for (const int gauge : {22, 25}) {
        for (const double depth : {40.0, 50.0}) {
            const double slope = deflection(gauge, 89.0, depth) / (depth / 10.0);
            EXPECT_NEAR(slope, 1.0, kDrummondRelative) << gauge << " G at " << depth << " mm [mm/cm]";
        }
    }
    // Control: at 10 mm, where the free shaft is long, the model's slope is far above
    // Drummond's (2.8 mm/cm for 22 G): the comparison can fail.
    EXPECT_GT(deflection(22, 89.0, 10.0) / 1.0, 1.0 + kDrummondRelative);
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
