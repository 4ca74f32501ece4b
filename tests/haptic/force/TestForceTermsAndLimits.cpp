// SPDX-License-Identifier: Apache-2.0
/// @file TestForceTermsAndLimits.cpp
/// @brief Issue 23 items 4, 6 and 7 on the force model: the [LP] bone texture
/// (physics.md §4), Kyung's gravity compensation F_G = −m·g (§1.1), the needle
/// gauge on the fixed [LP] and Conci tables (§3.3), Conci from labels with a
/// tissue that has no puncture force, and the device limiter's events.

#include "common/BuiltinTable.h"

#include "core/Format.h"
#include "haptic/force/NeedleForceModel.h"
#include "haptic/papers/ConciModel.h"
#include "haptic/papers/LayerTables.h"
#include "haptic/papers/LumbarPunctureModel.h"
#include "haptic/scene/ScriptedInsertion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace voxhap::haptic {
namespace force_terms_test {

using voxhap::test::table;

/// Sums of a handful of doubles of order 1–20 N: round-off of order 1e-14 N.
constexpr double kRoundOffN = 1e-12;

const NeedlePath kPath{Vec3d(0, 0, 0), Vec3d(0, 0, 1)};

DeviceLimits benchDevice()
{
    DeviceLimits d;
    d.name = "bench";
    d.maxForceN = d.maxContinuousForceN = 1e3;
    d.maxStiffnessNPerMm = 100.0;
    d.maxDampingNsPerMm = 1.0;
    return d;
}

ForceTerms lpTerms(bool texture)
{
    ForceTerms t;
    t.tip = t.cutting = t.viscous = true;
    t.karnoppDeltaVMmPerS = 1.0;
    t.critical = false;
    t.boneTexture.on = texture;
    t.boneTexture.cN = 0.3;
    return t;
}

LayerRecipe lpRecipe(double gaugeScale = 1.0)
{
    LayerRecipe r;
    r.model = LayerModel::LumbarPuncture;
    r.forceScale = gaugeScale;
    return r;
}

/// Axial force at each tick of a constant-speed insertion from @p from to @p to.
std::vector<std::pair<double, double>> profile(NeedleForceModel& m, double from, double to, double speed)
{
    std::vector<std::pair<double, double>> out;
    const double dt = 1e-3;
    const long n = std::lround((to - from) / (speed * dt));
    NeedleOutput o;
    for (long i = 0; i <= n; ++i) {
        const double d = from + double(i) * speed * dt;
        NeedleInput in;
        in.timeS = double(i) * dt;
        in.dtS = dt;
        in.tip = kPath.origin + d * kPath.direction;
        in.direction = kPath.direction;
        in.velocity = speed * kPath.direction;
        m.step(in, o);
        out.emplace_back(d, o.axialN);
    }
    return out;
}

/// physics.md §4: "Bone texture: f = −c·sgn(v) for |v| > 0", c = 0.3 N [chosen]. On
/// [LP] Table I at 20 mm/s the texture adds exactly c while the tip is in the bone
/// row (from 43 mm past the skin) and nothing before it: the stick-slip proxy
/// renders it as a Coulomb term (§6.2), slipping at c + C (the bone row's C is 0).
TEST(BoneTexture, AddsCWhileTheTipIsInBoneAndNothingElsewhere)
{
    const auto layers = fixedLayers(lpRecipe(), table());
    const auto build = [&](bool texture) {
        return NeedleForceModel(ForceModelSetup{
            .layers = layers, .path = kPath, .terms = lpTerms(texture), .needle = Needle{}, .device = benchDevice()});
    };
    NeedleForceModel with = build(true), without = build(false);
    const auto a = profile(with, -5.0, 49.99, 20.0);
    const auto b = profile(without, -5.0, 49.99, 20.0);
    ASSERT_EQ(a.size(), b.size());
    // The proxy climbs to the new threshold at k_c = 100 N/mm: 0.003 mm, inside the
    // first 0.02 mm tick; a tick either side of the bone's face is left out.
    const double tick = 20.0 * 1e-3;
    int inBone = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const double d = a[i].first;
        if (std::abs(d - 43.0) <= tick + 1e-9) continue;
        const double expected = d > 43.0 ? 0.3 : 0.0;
        EXPECT_NEAR(a[i].second - b[i].second, expected, kRoundOffN) << "at " << d << " mm";
        inBone += d > 43.0;
    }
    EXPECT_GT(inBone, 300); // 43..49.99 mm at 0.02 mm per tick
}

// Standing still on the bone (v = 0) the texture is 0 (§4 "else 0"): the proxy's
// threshold drops to the bone row's C = 0 and its spring lets go.
TEST(BoneTexture, IsZeroAtRest)
{
    ForceTerms t = lpTerms(true);
    TipState tip;
    const auto layers = fixedLayers(lpRecipe(), table());
    tip.pushLayer = int(layers.size()) - 1; // the bone row, tenting
    ASSERT_EQ(layers.back().role, LayerRole::Bone);
    EXPECT_NEAR(tipSlipForceN(t, tip, layers, 5.0), 0.3, kRoundOffN);
    EXPECT_NEAR(tipSlipForceN(t, tip, layers, -5.0), 0.3, kRoundOffN); // the proxy gives it the motion's sign
    EXPECT_EQ(tipSlipForceN(t, tip, layers, 0.0), 0.0);
    t.boneTexture.on = false;
    EXPECT_EQ(tipSlipForceN(t, tip, layers, 5.0), 0.0);
}

/// physics.md §1.1 Eq. 1, F = F_R + F_C + F_G, with F_G = −m·g (the clarification of
/// issue 23): a 0.2 kg handle under gravity along −y needs 0.2·9.80665 N along +y.
/// Out of the body the tissue terms are zero, so the rendered force is F_G to
/// round-off, whichever way the handle moves: the passivity observer does not count
/// it (the handle's weight takes its work back) and adds no damping.
TEST(Gravity, RenderedForceIsMinusMgOutOfTheBody)
{
    const std::vector<Layer> layers = {Layer{.name = "skin", .role = LayerRole::Skin, .startMm = 50, .endMm = 60}};
    DeviceLimits dev = benchDevice();
    dev.handleMassKg = 0.2;
    dev.down = {0.0, -2.0, 0.0}; // any length: the direction is what counts
    ForceTerms terms;
    terms.critical = false;
    NeedleForceModel m(
        ForceModelSetup{.layers = layers, .path = kPath, .terms = terms, .needle = Needle{}, .device = dev});
    const Vec3d expected(0.0, 0.2 * 9.80665, 0.0);
    NeedleOutput o;
    for (int i = 0; i < 2000; ++i) { // up and down along y and z, 20 mm/s: lifting and lowering
        const double s = std::sin(2.0 * kPi * i / 500.0);
        NeedleInput in;
        in.timeS = i * 1e-3;
        in.tip = Vec3d(0.0, 10.0 * s, 10.0 * s);
        in.direction = kPath.direction;
        in.velocity = Vec3d(0.0, 1.0, 1.0) * (20.0 * kPi * std::cos(2.0 * kPi * i / 500.0));
        m.step(in, o);
        ASSERT_NEAR((o.force - expected).norm(), 0.0, kRoundOffN) << "tick " << i;
        ASSERT_NEAR((o.terms.gravity - expected).norm(), 0.0, kRoundOffN);
    }
    EXPECT_EQ(o.limitedN, 0.0);
}

// The default handle mass is 0 (a device that compensates in firmware): no F_G.
TEST(Gravity, DefaultDeviceHasNoGravityTerm)
{
    EXPECT_EQ(DeviceLimits{}.handleMassKg, 0.0);
    EXPECT_EQ(deviceLimits("phantom-premium").handleMassKg, 0.0);
    NeedleForceModel m(ForceModelSetup{.layers = {}, .path = kPath, .terms = {}, .needle = Needle{}, .device = {}});
    NeedleOutput o;
    NeedleInput in;
    m.step(in, o);
    EXPECT_EQ(o.force.norm(), 0.0);
}

// A handle heavier than the device can hold: F_G = 1 kg · g = 9.81 N against a 3.3 N
// peak. The peak limit cuts it to 3.3 N (direction kept), says so with one
// ForceLimited event when it starts, and reports the cut each tick.
TEST(DeviceLimiter, ActionIsAnEventWithTheCut)
{
    DeviceLimits dev; // touch: 3.3 N peak, 0.88 N continuous
    dev.handleMassKg = 1.0;
    NeedleForceModel m(ForceModelSetup{.layers = {}, .path = kPath, .terms = {}, .needle = Needle{}, .device = dev});
    NeedleOutput o;
    int events = 0;
    for (int i = 0; i < 10; ++i) {
        NeedleInput in;
        in.timeS = i * 1e-3;
        m.step(in, o);
        for (const Event& e : o.events) events += e.type == EventType::ForceLimited;
        if (i == 0) {
            // The first tick: the rise limit (2 N per 1 ms tick) comes after the peak.
            EXPECT_NEAR(o.limitedN, 9.80665 - 3.3, 1e-9);
        }
    }
    EXPECT_EQ(events, 1) << "one event when the limiter starts acting, not one per tick";
    EXPECT_GT(o.limitedN, 9.80665 - 3.3 - 1e-9); // still cut; the I²t allowance only falls
    EXPECT_NEAR(o.force.normalized().y(), 1.0, 1e-12);
}

/// physics.md §3.3 (Needle.h): the tip's forces scale with d/d_ref. The fixed [LP]
/// table's k and C scale by it, its shaft viscosity b does not; the fixed Conci
/// table's forces (S_f,max, plateaus) scale by it, its depths do not.
TEST(GaugeScale, FixedTablesScaleTheirTipForces)
{
    const double s = gaugeOuterDiameterMm(18) / gaugeOuterDiameterMm(22); // 1.270/0.718
    const auto one = fixedLayers(lpRecipe(), table()), scaled = fixedLayers(lpRecipe(s), table());
    ASSERT_EQ(one.size(), scaled.size());
    for (std::size_t i = 0; i < one.size(); ++i) {
        EXPECT_NEAR(scaled[i].elastic[1], s * one[i].elastic[1], kRoundOffN) << one[i].name;
        EXPECT_NEAR(scaled[i].coulombN, s * one[i].coulombN, kRoundOffN) << one[i].name;
        EXPECT_EQ(scaled[i].viscousNsPerMm2, one[i].viscousNsPerMm2) << one[i].name;
        EXPECT_EQ(scaled[i].endMm, one[i].endMm) << one[i].name;
    }
    // [LP] Table I: skin k = 330 N/m, C = 0.3 N (physics.md §4), at the scaled gauge.
    EXPECT_NEAR(scaled[1].elastic[1], 0.330 * s, kRoundOffN);
    EXPECT_NEAR(scaled[1].coulombN, 0.3 * s, kRoundOffN);

    LayerRecipe c;
    c.model = LayerModel::Conci;
    c.tip = TipType::Coned;
    const auto conci1 = fixedLayers(c, table());
    c.forceScale = s;
    const auto conciS = fixedLayers(c, table());
    ASSERT_EQ(conci1.size(), conciS.size());
    for (std::size_t i = 0; i < conci1.size(); ++i) {
        EXPECT_NEAR(conciS[i].punctureForceN, s * conci1[i].punctureForceN, 1e-12 * s * conci1[i].punctureForceN);
        EXPECT_NEAR(conciS[i].plateau[0], s * conci1[i].plateau[0], kRoundOffN);
        EXPECT_EQ(conciS[i].punctureDepthMm, conci1[i].punctureDepthMm);
    }
    // §3.2's skin: S_f,max = 6.037 N at the reference gauge.
    EXPECT_NEAR(conciS[0].punctureForceN, 6.0372 * s, 1e-9);
}

/// Issue 23 item 7: Conci from labels, with a tissue the table gives no puncture
/// force (soft_tissue) between skin and muscle: it takes kConciDefaultPunctureN
/// (4.354 N, [C-ui]'s muscle) instead of throwing. With a coned tip (slope ×1) the
/// fit of §3.2 puts each layer's elastic maximum S_f,max at its puncture force P.
TEST(ConciLabels, TissueWithoutPunctureForceTakesTheDefault)
{
    ASSERT_FALSE(table().at("soft_tissue").punctureForce.has_value());
    const std::vector<LabelRun> runs = {{table().at("skin").id, 0.0, 2.0}, {table().at("soft_tissue").id, 2.0, 7.0},
        {table().at("muscle").id, 7.0, 10.0}};
    LayerRecipe r;
    r.model = LayerModel::Conci;
    r.tip = TipType::Coned;
    std::vector<Layer> layers;
    ASSERT_NO_THROW(layers = layersFromRuns(runs, table(), r));
    ASSERT_EQ(layers.size(), 3u);
    EXPECT_NEAR(layers[0].punctureForceN, table().at("skin").punctureForce->value, 1e-12);
    EXPECT_NEAR(layers[1].punctureForceN, kConciDefaultPunctureN, 1e-12);
    EXPECT_NEAR(layers[1].punctureDepthMm, 0.6 * 5.0, 1e-12); // §3.2 step 2: u_p = 0.6·Z_t
    // §3.2 step 3: the soft tissue's elastic stage starts at the skin's plateau,
    // Cp0 = 0.5·min(P_skin, P_soft) (step 4).
    EXPECT_NEAR(layers[1].elastic[0], 0.5 * std::min(6.0372, kConciDefaultPunctureN), 1e-12);
}

/// Item 7 for [LP] from labels: each label run is a layer with the tissue table's
/// k, b and C ([LP] Eq. 2–3), k and C at the needle's gauge.
TEST(LumbarPunctureLabels, LayersCarryTheTableValuesAtTheGauge)
{
    const std::vector<LabelRun> runs = {{table().at("skin").id, 0.0, 2.0}, {table().at("fat").id, 2.0, 9.0},
        {table().at("ligamentum_flavum").id, 9.0, 15.0}};
    const double s = 0.8;
    const auto layers = layersFromRuns(runs, table(), lpRecipe(s));
    ASSERT_EQ(layers.size(), 3u);
    for (std::size_t i = 0; i < runs.size(); ++i) {
        const volume::Tissue& t = *table().find(runs[i].label);
        const double k = t.elasticity ? t.elasticity->value : 0.0;
        EXPECT_NEAR(layers[i].elastic[1], k * s, kRoundOffN) << t.name;
        EXPECT_EQ(layers[i].tents, k > 0.0) << t.name;
        EXPECT_NEAR(layers[i].coulombN, t.frictionCoulomb->value * s, kRoundOffN) << t.name;
        EXPECT_NEAR(layers[i].viscousNsPerMm2, t.frictionViscous->value, kRoundOffN) << t.name;
        if (k > 0.0) {
            EXPECT_NEAR(layers[i].punctureDepthMm, runs[i].endMm - runs[i].startMm, 1e-12) << t.name;
        }
    }
}

// Reports never print a negative zero: a surface met at -1e-15 mm reads "0.0".
TEST(Format, NoNegativeZero)
{
    EXPECT_EQ(fixed(-1e-15), "0.0");
    EXPECT_EQ(fixed(-0.0, 2), "0.00");
    EXPECT_EQ(fixed(-0.04), "0.0");
    EXPECT_EQ(fixed(-0.06), "-0.1");
    EXPECT_EQ(fixed(12.25, 1), "12.2"); // as std::fixed rounds (to even on a tie)
}

} // namespace force_terms_test
} // namespace voxhap::haptic
