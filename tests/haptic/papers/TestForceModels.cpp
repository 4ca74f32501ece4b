// SPDX-License-Identifier: Apache-2.0
/// @file TestForceModels.cpp
/// @brief The regression phantoms of physics.md §7: R2 (lumbar-puncture table),
/// R3 (Conci profile), R4 (Sénac nested boxes), R6 (bone transient), R7 (Kelvin step).

#include "common/Tolerances.h"

#include "haptic/force/ContactTransient.h"
#include "haptic/force/PivotCorrection.h"
#include "haptic/papers/ConciModel.h"
#include "haptic/papers/LumbarPunctureModel.h"
#include "haptic/papers/SenacModel.h"

#include <cmath>

namespace voxhap::haptic {
namespace {

// physics.md §7 R2
TEST(LumbarPunctureModel, LumbarPunctureTableReproducesThePrintedForces)
{
    // physics.md §4, reference |f| at v = 0.02 m/s, to 1e-6 N beyond the printed digits:
    // the printed values are rounded to 4 decimals, so compare with half a unit in the last place.
    const std::vector<std::pair<double, double>> reference{{6.0, 0.6300}, {6.99, 0.9568}, {10.0, 0.3001},
        {20.0, 3.8006}, {29.99, 9.2957}, {32.0, 2.5613}, {34.99, 5.4917}, {40.0, 0.2017}, {50.0, 4.7419},
        {54.99, 16.568}};
    for (const auto& [depth, magnitude] : reference) {
        const double f = lumbarPunctureForce(lpTable(), depth, 20.0, +1);
        const double halfUlp = depth == 54.99 ? 5e-4 : 5e-5; // 16.568 has three decimals
        EXPECT_NEAR(std::abs(f), magnitude, halfUlp + 1e-6) << "depth " << depth;
        EXPECT_LT(f, 0.0) << "resists insertion";
    }
}

// physics.md §7 R2
TEST(LumbarPunctureModel, ClosedFormAtAnyDepthAndSpeed)
{
    // Independent evaluation of Eq. 1–3 at 20 mm depth (ligament: x = 6 mm, C = 0.5 N):
    // k·x + C + v·(2.1·2 + 1.0·7 + 3.0·6)·1e-3 with v in m/s.
    for (double v : {11.0, 20.0, 50.0}) { // above Δv = 10 mm/s: Coulomb term on
        const double expected = 550.0 * 0.006 + 0.5 + (v * 1e-3) * (2.1 * 2 + 1.0 * 7 + 3.0 * 6) * 1e-3;
        EXPECT_NEAR(-lumbarPunctureForce(lpTable(), 20.0, v, +1), expected, 1e-12);
    }
    // Below Δv the Karnopp band leaves only viscosity.
    EXPECT_NEAR(-lumbarPunctureForce(lpTable(), 20.0, 5.0, +1), 3.3 + 5e-3 * 29.2e-3, 1e-12);
    // v <= 0: f_keepdir = 0.001 N in the last motion direction (Eq. 1).
    EXPECT_EQ(lumbarPunctureForce(lpTable(), 20.0, 0.0, +1), 0.001);
    EXPECT_EQ(lumbarPunctureForce(lpTable(), 20.0, -3.0, -1), -0.001);
    EXPECT_EQ(lumbarPunctureForce(lpTable(), std::nan(""), 3.0, 1), 0.0);
}

// physics.md §7 R3
TEST(ConciModel, FittedTableMatchesThePrintedOne)
{
    // physics.md §3.2 "Fitted table (computed)", to its printed digits.
    struct Row {
        double zStart, zt, up, ce0, ce1, ce2, sfMax, tf, cp0;
    };
    const std::vector<Row> printed{
        {0, 10.8, 6.48, 0, 0.4658, 0.07189, 6.037, 5.050, 0.987},
        {10.8, 2.8, 1.68, 0.987, 0.2938, 0.17485, 1.974, 0.987, 0.987},
        {13.6, 1.9, 1.14, 0.987, 1.4768, 1.29540, 4.354, 2.177, 2.177},
        {15.5, 18.0, 10.8, 2.177, 0.2449, 0.02268, 7.467, 3.733, 3.733},
        {33.5, 7.4, 7.4, 3.733, 0.5675, 0.07669, 12.133, 10.914, 1.218},
        {40.9, 8.6, 8.6, 1.218, 0.0708, 0.00824, 2.437, 1.218, 1.218},
    };
    const auto layers = fitConci(conciSeeds());
    ASSERT_EQ(layers.size(), printed.size());
    for (std::size_t i = 0; i < printed.size(); ++i) {
        const Row& r = printed[i];
        const ConciLayer& l = layers[i];
        SCOPED_TRACE(l.name);
        // Each printed number is rounded: allow half a unit of its last printed digit
        // (5e-4 for three decimals), plus round-off in our own arithmetic.
        constexpr double kHalfUnit = 5e-4 + 1e-9;
        EXPECT_NEAR(l.zStartMm, r.zStart, 1e-9);
        EXPECT_NEAR(l.thicknessMm, r.zt, 1e-9);
        EXPECT_NEAR(l.punctureDepthMm, r.up, 1e-9);
        EXPECT_NEAR(l.ce0, r.ce0, kHalfUnit);
        EXPECT_NEAR(l.ce1, r.ce1, 5e-4 * r.ce1 + 5e-5);
        EXPECT_NEAR(l.ce2, r.ce2, 5e-4 * r.ce2 + 5e-6);
        EXPECT_NEAR(l.sfMaxN, r.sfMax, kHalfUnit);
        EXPECT_NEAR(l.tfN, r.tf, kHalfUnit);
        EXPECT_NEAR(l.cp0, r.cp0, kHalfUnit);
    }
}

// physics.md §7 R3
TEST(ConciModel, ProfileIsContinuousWithinStagesAndDropsExactlyTf)
{
    const auto layers = fitConci(conciSeeds());
    ConciModel model(layers);
    double prev = model.update(0.0).forceN;
    int pops = 0;
    constexpr double kStep = 1e-4; // mm; the steepest slope is 4.43 N/mm (muscle), so 4.5e-4 N per step
    for (double z = kStep; z < 49.5; z += kStep) {
        const auto o = model.update(z);
        if (o.punctured) {
            ++pops;
            // The drop at puncture is T_f of the layer that was punctured, exactly,
            // up to how far the step overshot u_p (at most one step of the steepest slope).
            const ConciLayer& l = layers[std::size_t(pops - 1)];
            EXPECT_NEAR(prev - o.forceN, l.tfN, 4.5e-4 + 1e-9) << l.name << " at z " << z;
        } else {
            EXPECT_LE(std::abs(o.forceN - prev), 4.5e-4 + 1e-12) << "discontinuity at z " << z;
        }
        prev = o.forceN;
    }
    EXPECT_EQ(pops, 5); // skin, fat, muscle, interspinous, flavum (the last is reached, not left)
    // §7 R3: 12.133 -> 1.218 N at z = 40.9 mm (the flavum's depth-triggered puncture).
    ConciModel fresh(layers);
    for (double z = 0.0; z < 40.9 - 1e-9; z += 0.01) fresh.update(z);
    EXPECT_NEAR(fresh.update(40.9 - 1e-9).forceN, 12.133, 1e-6);
    const auto after = fresh.update(40.9);
    EXPECT_TRUE(after.punctured);
    EXPECT_NEAR(after.forceN, 1.218, 5e-4);
}

// physics.md §7 R3
TEST(ConciModel, BmiScalesTheLayersAboveTheEpiduralSpace)
{
    // §3.3: BMI 30 -> s = 1.423 (printed), SED 58.2 mm.
    const double s = conciBmiScale(30.0);
    EXPECT_NEAR(s, 1.423, 5e-4);
    const auto layers = fitConci(conciSeeds(), s);
    EXPECT_NEAR(layers.back().zStartMm, 58.2, 1e-9);
    EXPECT_NEAR(layers.back().thicknessMm, 8.6, 1e-12); // the epidural space and dura are not scaled
    const auto bevel = fitConci(conciSeeds(), 1.0, TipType::Bevel);
    EXPECT_NEAR(bevel[0].ce1, 0.85 * fitConci(conciSeeds())[0].ce1, 1e-12);
}

// physics.md §7 R4
TEST(SenacModel, SenacNestedBoxesAndPrePunctureStiffness)
{
    // §2.2: F_p = 2 N at z_p = 10 mm -> a1 = 0.10 N/mm, a2 = 0.010 N/mm², peak slope 0.30 N/mm.
    const auto k = PrePunctureStiffness::fromPuncture(2.0, 10.0);
    EXPECT_NEAR(k.a1NPerMm, 0.10, 1e-15);
    EXPECT_NEAR(k.a2NPerMm2, 0.010, 1e-15);
    EXPECT_NEAR(k.slopeNPerMm(10.0), 0.30, 1e-15);
    for (double z : {0.5, 3.0, 7.25, 10.0}) {
        const double expected = 0.10 * z + 0.010 * z * z;
        EXPECT_NEAR(k.forceN(z), expected, 1e-12 * expected);
    }
    EXPECT_EQ(k.forceN(-1.0), 0.0);
    // Fig. 3 standard case: derma 2, supraspinous 4, interspinous 4, flavum 6 N; in the flavum
    // the boxes sum to 16 N (§2.3 [chosen reading]).
    NestedBoxCutting cut{{{0.0, 2.0}, {10.0, 4.0}, {13.0, 4.0}, {28.0, 6.0}}, 0.2};
    EXPECT_EQ(cut.forceN(30.0, 2.0), 16.0);
    EXPECT_EQ(cut.forceN(12.0, 2.0), 6.0);
    EXPECT_EQ(cut.forceN(30.0, 0.1), 0.0);   // below ε
    EXPECT_EQ(cut.forceN(30.0, -2.0), 16.0); // opposes motion either way
}

// physics.md §7 R6
TEST(ContactTransient, BoneTransientSamplesTheDecayingSine)
{
    const ContactTransient c; // A = 150 N·s/m, d = 40 ms, f = 100 Hz
    const double vIn = 10.0;  // mm/s
    constexpr double kT = 1e-3;
    for (int n = 1; n <= 40; ++n) {
        const double t = n * kT;
        const double expected = -150.0 * std::exp(std::log(0.01) * t / 0.040) * std::sin(2.0 * kPi * 100.0 * t) * 0.010;
        EXPECT_NEAR(c.forceN(t, vIn), expected, 1e-12 * std::max(1.0, std::abs(expected))) << n;
    }
    EXPECT_EQ(c.forceN(0.041, vIn), 0.0);
    EXPECT_EQ(c.forceN(0.0, vIn), 0.0);
    // First peak 0.763·A·|v_in| at 2.21 ms (§2.2, computed): maximise on a fine grid.
    double peak = 0, at = 0;
    for (double t = 1e-6; t < 0.005; t += 1e-6) {
        if (std::abs(c.forceN(t, vIn)) > peak) peak = std::abs(c.forceN(t, vIn)), at = t;
    }
    EXPECT_NEAR(peak, 0.763 * 150.0 * 0.010, 5e-4 * 1.5); // three printed digits
    EXPECT_NEAR(at, 2.21e-3, 5e-6);
    // The clamp: a 100 mm/s impact would peak at 11 N; capped at 2 N.
    EXPECT_NEAR(std::abs(c.forceN(at, 100.0)), 2.0, 1e-12);
}

// physics.md §7 R7
TEST(PivotCorrection, KelvinStepResponseIsExactlyGeometric)
{
    const double k1 = 0.5, k2 = 0.8, tau = 0.02, period = 1e-3, x = 2.0;
    KelvinElement e(k1, k2, tau);
    for (int n = 1; n <= 200; ++n) {
        const double expected = k1 * x + k2 * x * std::pow(tau / (tau + period), n); // §7 R7, backward Euler
        EXPECT_NEAR(e.step(x, period), expected, 1e-12 * expected) << n;
    }
    // dt jitter (§6.4): zero, tiny, huge and NaN periods never divide by zero and stay bounded.
    for (double dt : {0.0, 1e-6, 0.5e-3, 2e-3, 1e-2, 1.0, std::nan("")}) {
        KelvinElement j(k1, k2, tau);
        for (int n = 0; n < 10; ++n) {
            const double f = j.step(x, dt);
            ASSERT_TRUE(std::isfinite(f));
            ASSERT_LE(f, (k1 + k2) * x + 1e-12);
            ASSERT_GE(f, k1 * x - 1e-12);
        }
    }
}

// physics.md §7 R7
TEST(PivotCorrection, PivotCorrectionMeetsItsDesignPointAndCap)
{
    // §1.4 defaults: F_C = 2 N at θ = 10°, D = 60 mm, L_h = 30 mm once relaxed (k1 only).
    PivotCorrection pivot;
    const double theta = 10.0 * kPi / 180.0;
    double f = 0;
    for (int n = 0; n < 2000; ++n) f = pivot.update(theta, 60.0, 1e-3); // 2 s >> τ = 20 ms
    // κ1 = 3·L_h·F_C/(θ·D³) is printed as 4.8e3 N/m² (two digits); the layer sum Σ r_i² h
    // approaches D³/3 with midpoint r_i (error h²D/12 relative to D³/3: 7e-5).
    EXPECT_NEAR(f, 2.0, 2.0 * (0.005 + 1e-4));
    // Instantly after a step the stiffness is k1 + k2: the cap holds.
    PivotCorrection fresh;
    EXPECT_LE(std::abs(fresh.update(theta, 60.0, 1e-3)), 2.0);
    EXPECT_EQ(std::abs(fresh.update(3.0 * theta, 60.0, 1e-3)), 2.0);
    EXPECT_EQ(fresh.update(std::nan(""), 60.0, 1e-3), 0.0);
}

} // namespace
} // namespace voxhap::haptic
