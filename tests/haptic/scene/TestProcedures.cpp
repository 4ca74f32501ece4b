// SPDX-License-Identifier: Apache-2.0
/// @file TestProcedures.cpp
/// @brief Issue 23 items 4–7 on the built-in scenes: the kyung scene's skin tents
/// and pops once; its rendered profile rises wherever the model's does up to bone
/// contact under its own device limits; success per procedure (Procedure.h); the
/// label-driven Conci and lumbar-puncture scenes against their closed forms.

#include "common/BuiltinTable.h"
#include "common/SceneCache.h"

#include "core/Errors.h"
#include "haptic/Procedure.h"
#include "haptic/scene/Scene.h"
#include "haptic/scene/ScriptedInsertion.h"
#include "haptic/servo/Session.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>

namespace voxhap::haptic {
namespace procedures_test {

using voxhap::test::table;

const SceneInstance& instance(const std::string& name) { return test::sceneInstance(name); }

InsertionResult simulate(const SceneInstance& inst, NeedleForceModel& model, std::optional<double> depth = std::nullopt)
{
    const Scene& s = inst.scene();
    const double to = depth.value_or(s.depthMm.value_or((inst.target() - inst.entry()).norm()));
    return runInsertion(
        model, InsertionScript::constantSpeed(-s.approachMm, to, s.speedMmPerS), s.rateHz, s.success, inst.target());
}

InsertionResult simulate(const SceneInstance& inst, std::optional<double> depth = std::nullopt)
{
    auto model = inst.makeModel();
    return simulate(inst, *model, depth);
}

double tick(const Scene& s) { return s.speedMmPerS / s.rateHz; }

std::vector<double> depthsOf(const InsertionResult& r, EventType t)
{
    std::vector<double> d;
    for (const Event& e : r.events) {
        if (e.type == t) d.push_back(e.depthMm);
    }
    return d;
}

const Layer& layerNamed(const std::vector<Layer>& layers, const std::string& name)
{
    for (const Layer& l : layers) {
        if (l.name == name) return l;
    }
    throw std::runtime_error("no layer " + name);
}

/// Item 4: the kyung scene tents its skin ([K01] §1.1 deforms the skin before it gives
/// way) with §2.2's constants from the tissue table: P = 6.0372 N, k = 330 N/m, so
/// z_p = P/(2k) = 9.147 mm past where the tip meets it. One pop, within a tick.
TEST(KyungScene, SkinTentsAndPopsOnce)
{
    const SceneInstance& inst = instance("kyung");
    const InsertionResult r = simulate(inst);
    const Layer& skin = layerNamed(inst.layers(), "skin");
    const double zp = 6.0372 / (2.0 * 0.330);
    ASSERT_EQ(r.summary.pops, 1);
    EXPECT_NEAR(depthsOf(r, EventType::Pop).at(0), skin.startMm + zp, tick(inst.scene()) + 1e-9);
    EXPECT_NEAR(r.summary.skinEntryMm, skin.startMm + zp, tick(inst.scene()) + 1e-9);
    const std::string text = insertionSummaryText(r, inst.layers());
    EXPECT_EQ(text.find("-0.0"), std::string::npos) << text;
}

/// Item 6 (and its clarification): on the kyung scene's own insertion, under its own
/// device limits (PHANToM class, 8.5 N peak, 1.4 N continuous) and force_scale 0.5,
/// the rendered force rises wherever the model's rises, up to bone contact; the
/// limiter does not act before it; and the rendered force is the model's times the
/// scale there (uniform: the layers' contrasts survive). At force_scale 1 the same
/// check fails: the I²t budget is spent before the bone (what the issue measured).
TEST(KyungScene, RenderedProfileRisesWithTheModelUpToBoneContact)
{
    const SceneInstance& inst = instance("kyung");
    const auto check = [&](const InsertionResult& r, double scale, int& falls, int& limitsBefore) {
        const double contact = depthsOf(r, EventType::BoneContact).at(0);
        falls = 0, limitsBefore = 0;
        for (const double d : depthsOf(r, EventType::ForceLimited)) limitsBefore += d < contact;
        for (std::size_t i = 1; i < r.rows.size() && r.rows[i].depthMm < contact; ++i) {
            const InsertionRow &a = r.rows[i - 1], &b = r.rows[i];
            // The rendered force is along the path (no lateral terms on a straight line).
            if (b.axialN > a.axialN && b.force.norm() < a.force.norm() - 1e-12) ++falls;
            if (scale == inst.scene().terms.renderScale) {
                EXPECT_NEAR(b.force.norm(), scale * std::abs(b.axialN), 1e-12 * std::abs(b.axialN) + 1e-15)
                    << "at " << b.depthMm << " mm";
            }
        }
    };
    ASSERT_EQ(inst.scene().terms.renderScale, 0.5);
    int falls = 0, limits = 0;
    check(simulate(inst), 0.5, falls, limits);
    EXPECT_EQ(falls, 0);
    EXPECT_EQ(limits, 0);

    // The same model at force_scale 1: every term read from the scene, the voxel
    // damping through the exact traversal (the same force as the scene's locked
    // profile, TestScenes.cpp LockedProfileMatchesExactTraversal).
    ForceTerms terms = inst.scene().terms;
    terms.renderScale = 1.0;
    IntegratorOptions io;
    io.trackLabels = true;
    NeedleForceModel unscaled(ForceModelSetup{.layers = inst.layers(),
        .path = NeedlePath{inst.entry(), inst.target() - inst.entry()},
        .terms = terms,
        .needle = inst.scene().needle,
        .device = inst.scene().device,
        .integrator = makeIntegrator(*inst.field(), io),
        .field = inst.field()});
    check(simulate(inst, unscaled), 1.0, falls, limits);
    EXPECT_GT(falls, 0) << "the check must be able to fail";
    EXPECT_GT(limits, 0);
}

/// Item 5: a spine biopsy succeeds when the tip comes within the stated radius of
/// the target (the kyung scene: 8 mm, the lesion's radius) without a critical
/// breach. Inserted to the target: closest approach 0. Stopped 1 mm past the
/// bone contact: the closest approach is the rest of the path, and it fails.
TEST(Success, SpineBiopsyReachesTheTargetWithinTheRadius)
{
    const SceneInstance& inst = instance("kyung");
    ASSERT_EQ(inst.scene().success.rule, SuccessRule::ReachTarget);
    ASSERT_EQ(inst.scene().success.radiusMm, 8.0);
    const InsertionResult full = simulate(inst);
    EXPECT_TRUE(full.outcome.success) << full.outcome.reason;
    ASSERT_TRUE(full.outcome.targetDistanceMm);
    EXPECT_NEAR(*full.outcome.targetDistanceMm, 0.0, 1e-9);

    const double contact = full.summary.boneMm;
    const double length = (inst.target() - inst.entry()).norm();
    const InsertionResult stopped = simulate(inst, contact + 1.0);
    EXPECT_FALSE(stopped.outcome.success);
    ASSERT_TRUE(stopped.outcome.targetDistanceMm);
    // The tip moves on the straight path: its closest approach is where it stopped.
    EXPECT_NEAR(*stopped.outcome.targetDistanceMm, length - (contact + 1.0), 1e-9);
    EXPECT_NE(stopped.outcome.reason.find("outside the 8.0 mm radius"), std::string::npos) << stopped.outcome.reason;
}

// Epidural ([S19] §2.3): success while the dura stays intact; pushed on through it, not.
// Lumbar puncture ([LP] §4): success when the tip reaches the CSF.
TEST(Success, EpiduralAndLumbarPuncture)
{
    const SceneInstance& senac = instance("senac-average");
    EXPECT_TRUE(simulate(senac).outcome.success);
    const InsertionResult deep = simulate(senac, 50.0);
    EXPECT_FALSE(deep.outcome.success);
    EXPECT_NE(deep.outcome.reason.find("dura punctured at"), std::string::npos) << deep.outcome.reason;

    const SceneInstance& lp = instance("lumbar-puncture");
    EXPECT_EQ(lp.scene().success.rule, SuccessRule::ReachCsf);
    const InsertionResult through = simulate(lp);
    EXPECT_TRUE(through.outcome.success) << through.outcome.reason;
    EXPECT_TRUE(through.outcome.csfReached);
    EXPECT_FALSE(simulate(lp, 20.0).outcome.success); // stopped in the ligament
}

// Every rule fails on a critical breach; the tracker's closest approach is exact.
TEST(Success, CriticalBreachFailsEveryRule)
{
    const std::vector<Layer> layers = {Layer{.name = "csf", .role = LayerRole::Csf, .startMm = 0, .endMm = 1}};
    for (const SuccessRule rule : {SuccessRule::DuraIntact, SuccessRule::ReachCsf, SuccessRule::ReachTarget}) {
        OutcomeTracker t({rule, 5.0}, layers, Vec3d(0, 0, 10));
        t.addTip(Vec3d(3, 0, 10), 0); // 3 mm from the target, in the CSF
        EXPECT_TRUE(t.result().success) << successRuleName(rule);
        EXPECT_NEAR(*t.result().targetDistanceMm, 3.0, 1e-12);
        t.addEvent({EventType::CriticalBreach, 1.0, 4.0, 0});
        EXPECT_FALSE(t.result().success) << successRuleName(rule);
        EXPECT_NE(t.result().reason.find("critical breach at 4.0 mm"), std::string::npos) << t.result().reason;
    }
}

// serve's metrics (Session.h) judge the session by the scene's rule: records that
// pass 2 mm from the target succeed within a 3 mm radius; the limiter's events are
// counted; the dura's state is kept beside the rule's verdict.
TEST(Success, SessionMetricsFollowTheScenesRule)
{
    const std::vector<Layer> layers = {Layer{.name = "muscle", .role = LayerRole::Tissue, .startMm = 0, .endMm = 50}};
    const Vec3d target(2.0, 0.0, 30.0);
    TraineeMetricsAccumulator acc(layers, Vec3d(0, 0, 1), {SuccessRule::ReachTarget, 3.0}, target);
    acc.addEvent({EventType::ForceLimited, 0.5, 25.0, 0});
    acc.addEvent({EventType::ForceLimited, 0.9, 40.0, 0});
    for (int i = 0; i <= 100; ++i) { // along z from 0 to 50 mm, 2 mm beside the target
        ServoRecord r;
        r.timeS = 0.01 * i;
        r.depthMm = 0.5 * i;
        r.tip = Vec3d(0.0, 0.0, r.depthMm);
        r.layer = 0;
        acc.addRecord(r);
    }
    const TraineeMetrics m = acc.result();
    EXPECT_TRUE(m.success) << m.outcome.reason;
    EXPECT_TRUE(m.duraIntact);
    ASSERT_TRUE(m.outcome.targetDistanceMm);
    EXPECT_NEAR(*m.outcome.targetDistanceMm, 2.0, 1e-12);
    EXPECT_EQ(m.forceLimits, 2);
    TraineeMetricsAccumulator tight(layers, Vec3d(0, 0, 1), {SuccessRule::ReachTarget, 1.5}, target);
    ServoRecord r;
    r.tip = Vec3d(0.0, 0.0, 30.0);
    tight.addRecord(r);
    EXPECT_FALSE(tight.result().success);
}

// The new scene keys are read strictly: one line naming the file and the field.
TEST(SceneKeys, NewKeysAreReadAndBadOnesRefusedNamingTheField)
{
    const std::string head = R"({"schema": "voxhap-scene/1", "name": "x", "model": "kyung", "terms": {"tip": true)";
    const auto refusal = [](const std::string& json) {
        try {
            (void)parseScene(json, "s.json");
        } catch (const ValueError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    const Scene ok = parseScene(head + R"(, "bone_texture": {"c_N": 0.4}}, "force_scale": 0.25,
        "success": {"rule": "reach_target", "radius_mm": 3},
        "device": {"handle_mass_kg": 0.3, "down": [0, 0, -4]}})",
        "s.json");
    EXPECT_TRUE(ok.terms.boneTexture.on);
    EXPECT_EQ(ok.terms.boneTexture.cN, 0.4);
    EXPECT_EQ(ok.terms.renderScale, 0.25);
    EXPECT_EQ(ok.success.rule, SuccessRule::ReachTarget);
    EXPECT_EQ(ok.success.radiusMm, 3.0);
    EXPECT_EQ(ok.device.handleMassKg, 0.3);
    EXPECT_EQ(ok.device.down[2], -1.0); // normalised
    EXPECT_TRUE(ok.recipe.tenting.empty()) << "a kyung scene tents only what it names";
    EXPECT_EQ(parseScene(head + "}}", "s.json").success.rule, SuccessRule::ReachTarget); // kyung's default

    EXPECT_NE(
        refusal(head + R"(}, "force_scale": 0})").find("s.json: force_scale: must be in (0, 10]"), std::string::npos);
    EXPECT_NE(refusal(head + R"(}, "success": {"rule": "win"}})").find("s.json: success.rule: unknown success rule"),
        std::string::npos);
    EXPECT_NE(refusal(head + R"(}, "success": {"rule": "dura_intact", "radius_mm": 2}})")
                  .find("s.json: success.radius_mm: applies to the reach_target rule only"),
        std::string::npos);
    EXPECT_NE(refusal(head + R"(}, "device": {"down": [0, 0, 0]}})").find("s.json: device.down: must be a direction"),
        std::string::npos);
    EXPECT_NE(refusal(head + R"(, "bone_texture": {"c": 1}}})").find("s.json: terms.bone_texture.c: unknown field"),
        std::string::npos);
}

/// Item 7, Conci from the labels on the lumbar phantom's path: §3.2's fit on each
/// label run puts every pop at u_p from the run's start, 0.6·Z_t, or Z_t for the
/// depth-triggered flavum, epidural space and dura (step 2). Within a tick.
TEST(LabelScenes, ConciPopsWhereTheFitOnTheLabelRunsPutsThem)
{
    const SceneInstance& inst = instance("conci-labels");
    EXPECT_FALSE(inst.scene().fixedTable);
    const InsertionResult r = simulate(inst);
    std::vector<double> expected;
    for (const Layer& l : inst.layers()) {
        if (!l.tents || l.startMm > r.summary.finalDepthMm) continue;
        const bool depth = l.role == LayerRole::Epidural || l.role == LayerRole::Dura || l.name == "ligamentum_flavum";
        expected.push_back(l.startMm + (depth ? 1.0 : 0.6) * l.thicknessMm());
        EXPECT_NEAR(l.punctureDepthMm, (depth ? 1.0 : 0.6) * l.thicknessMm(), 1e-12) << l.name;
    }
    const std::vector<double> pops = depthsOf(r, EventType::Pop);
    ASSERT_GE(expected.size(), 6u); // skin, fat, two ligaments, flavum, epidural space, dura
    ASSERT_EQ(pops.size(), expected.size());
    for (std::size_t i = 0; i < pops.size(); ++i) EXPECT_NEAR(pops[i], expected[i], tick(inst.scene()) + 1e-9) << i;
    EXPECT_NEAR(
        depthsOf(r, EventType::DuraPuncture).at(0), layerNamed(inst.layers(), "dura").endMm, tick(inst.scene()) + 1e-9);
    EXPECT_TRUE(r.outcome.success) << r.outcome.reason;
}

/// Item 7, [LP] from the labels: within a layer, at constant speed v ≥ Δv,
/// f = k·x + C + v·Σ b_i·l_i (§4 Eq. 1–3, x from the layer's start, C of the layer
/// at the tip, b·l over the shaft), with the tissue table's k, b, C.
TEST(LabelScenes, LumbarPunctureFollowsTheLpLawOnTheLabelRuns)
{
    const SceneInstance& inst = instance("lumbar-puncture-labels");
    const Scene& s = inst.scene();
    ASSERT_EQ(s.needle.forceScale(), 1.0);
    const InsertionResult r = simulate(inst);
    const auto& layers = inst.layers();
    const double v = s.speedMmPerS;
    // The proxy climbs to a layer's new C at the device's k_c = 5 N/mm (0.12 mm for
    // 0.6 N): samples within 0.2 mm after a boundary, or a tick before one, are left out.
    int compared = 0;
    for (const InsertionRow& row : r.rows) {
        const double d = row.depthMm;
        int at = -1;
        double near = 1e9;
        for (int i = 0; i < int(layers.size()); ++i) {
            const Layer& l = layers[std::size_t(i)];
            near = std::min({near, d - l.startMm < 0 ? 1e9 : d - l.startMm, std::abs(l.endMm - d)});
            if (d > l.startMm && d < l.endMm) at = i;
        }
        if (at < 0 || near < 0.2 || layers[std::size_t(at)].role == LayerRole::Air) continue;
        double f = 0.0;
        for (const Layer& l : layers) f += l.viscousNsPerMm2 * v * std::max(0.0, std::min(d, l.endMm) - l.startMm);
        const Layer& l = layers[std::size_t(at)];
        const volume::Tissue& t = *table().find(l.label);
        f += (t.elasticity ? t.elasticity->value : 0.0) * (d - l.startMm);
        f += t.frictionCoulomb ? t.frictionCoulomb->value : 0.0;
        ASSERT_NEAR(row.axialN, f, 1e-9) << "at " << d << " mm in " << l.name;
        ++compared;
    }
    EXPECT_GT(compared, 1500); // ~49 mm at 0.02 mm per tick, less the margins
    EXPECT_TRUE(r.outcome.success) << r.outcome.reason;
}

} // namespace procedures_test
} // namespace voxhap::haptic
