// SPDX-License-Identifier: Apache-2.0
/// @file TestScenes.cpp
/// @brief Every built-in scene produces its events at the depths its paper and
/// phantom put them; scene files are parsed strictly; a scene builds only the
/// material grids its terms read.

#include "common/BuiltinTable.h"
#include "common/SceneCache.h"
#include "core/Errors.h"
#include "core/Math.h"
#include "haptic/scene/Scene.h"
#include "haptic/scene/ScriptedInsertion.h"
#include "phantoms/Phantoms.h"
#include "phantoms/Rasterize.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>

namespace voxhap::haptic {
namespace {

using voxhap::test::table;

/// Phantom voxels are 0.5 mm and interfaces sit on lattice faces: a layer boundary
/// on a straight path along a lattice axis moves by at most one voxel.
constexpr double kVoxelMm = 0.5;

struct SceneRun {
    InsertionResult result;
    std::vector<Layer> layers;
};

const SceneInstance& instance(const std::string& name) { return test::sceneInstance(name); }

SceneRun simulate(const std::string& name, std::optional<double> depth = std::nullopt)
{
    const SceneInstance& inst = instance(name);
    const Scene& scene = inst.scene();
    auto model = inst.makeModel();
    const double to = depth.value_or(scene.depthMm.value_or((inst.target() - inst.entry()).norm()));
    SceneRun r{
        runInsertion(*model, InsertionScript::constantSpeed(-scene.approachMm, to, scene.speedMmPerS), scene.rateHz),
        inst.layers()};
    return r;
}

double tick(const std::string& name)
{
    const Scene s = loadScene(name);
    return s.speedMmPerS / s.rateHz;
}

double first(const SceneRun& r, EventType t)
{
    for (const Event& e : r.result.events) {
        if (e.type == t) return e.depthMm;
    }
    return kNoLimit;
}

TEST(Scenes, AllBuiltinScenesParse)
{
    const std::vector<std::string> names = builtinSceneNames();
    for (const char* expected :
        {"kyung", "kyung-damping", "senac-average", "senac-overweight", "senac-calcified", "conci", "conci-labels",
            "lumbar-puncture", "lumbar-puncture-labels", "kyung-bending", "lumbar-puncture-bending"}) {
        EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
    }
    for (const std::string& n : names) EXPECT_NO_THROW(loadScene(n)) << n;
}

// [S19] Table I, average patient: derma 10 mm, supraspinous 3, interspinous 15, flavum
// 7.4 (tissue table) → epidural space at 35.4 mm; the derma pops when its tent reaches
// z_p = 10 mm (the scene's [chosen] §2.2 value); the path ends in the epidural space,
// so the dura stays intact (success, §2.3).
TEST(Scenes, SenacAverageSkinPopLorAndIntactDura)
{
    const SceneRun r = simulate("senac-average");
    EXPECT_NEAR(first(r, EventType::SkinEntry), 10.0, tick("senac-average") + 1e-9);
    EXPECT_NEAR(first(r, EventType::LossOfResistance), 35.4, kVoxelMm);
    EXPECT_EQ(first(r, EventType::DuraPuncture), kNoLimit);
    EXPECT_EQ(r.result.summary.breaches, 0);
    // The plunger is blocked in ligament and has dropped below 1 N 5 time constants
    // (0.75 s at 2 mm/s = 1.5 mm) after the loss of resistance ([S19] average LOR).
    double blocked = 0, after = kNoLimit;
    for (const InsertionRow& row : r.result.rows) {
        if (row.depthMm > 20.0 && row.depthMm < 30.0) blocked = std::max(blocked, row.plungerN);
        if (row.depthMm > first(r, EventType::LossOfResistance) + 1.5) after = std::min(after, row.plungerN);
    }
    EXPECT_NEAR(blocked, 10.0, 1e-12);
    EXPECT_LT(after, 10.0 * std::exp(-5.0) + 0.5 + 1e-9); // 0.05 resistance floor in the epidural space
}

// Deeper on the same patient: the dura (41.4–42.4 mm) tents until Table I's 8 N; with
// a1 = k = 0.98 N/mm, z_p = F/(2k) = 4.08 mm (LayerTables.h [chosen]) → pop at 45.48 mm.
TEST(Scenes, SenacAverageDuraPunctureWhenPushedOn)
{
    const SceneRun r = simulate("senac-average", 50.0);
    EXPECT_NEAR(first(r, EventType::DuraPuncture), 41.4 + 8.0 / (2.0 * 0.98), kVoxelMm + tick("senac-average"));
}

// Overweight: derma 30 mm, epidural 4 mm → LOR at 55.4 mm; calcified: derma 10 mm,
// epidural 4 mm, F_dura 14 N → LOR at 35.4 mm, dura pop at 39.4 + 14/1.96 = 46.54 mm.
TEST(Scenes, SenacOverweightAndCalcified)
{
    const SceneRun over = simulate("senac-overweight");
    EXPECT_NEAR(first(over, EventType::SkinEntry), 10.0, tick("senac-overweight") + 1e-9);
    EXPECT_NEAR(first(over, EventType::LossOfResistance), 55.4, kVoxelMm);
    EXPECT_EQ(first(over, EventType::DuraPuncture), kNoLimit);
    const SceneRun calc = simulate("senac-calcified", 50.0);
    EXPECT_NEAR(first(calc, EventType::LossOfResistance), 35.4, kVoxelMm);
    EXPECT_NEAR(first(calc, EventType::DuraPuncture), 39.4 + 14.0 / 1.96, kVoxelMm + tick("senac-calcified"));
}

// Conci at BMI 30: s = 1.423 (physics.md §3.3). The skin pops at u_p = 0.6·10.8·s
// = 9.221 mm (§3.2 step 2), the tip reaches the epidural space at SED = 58.2 mm, and
// the merged epidural/dura row (8.6 mm, not scaled) pops at its end, 66.8 mm. The
// printed s and SED have 3 and 1 decimals: tolerances are half their last digit
// (times the 40.9 mm it scales) plus one tick.
TEST(Scenes, ConciBmi30Depths)
{
    const SceneRun r = simulate("conci");
    const double t = tick("conci");
    EXPECT_NEAR(first(r, EventType::SkinEntry), 0.6 * 10.8 * 1.423, 0.6 * 10.8 * 0.0005 + t);
    EXPECT_NEAR(first(r, EventType::LossOfResistance), 58.2, 40.9 * 0.0005 + t);
    EXPECT_NEAR(first(r, EventType::DuraPuncture), 58.2 + 8.6, 40.9 * 0.0005 + t);
    EXPECT_EQ(r.result.summary.pops, 6);
}

// [LP] Table I ends less the 5 mm out of the skin: skin 2, ligament 25, dura 30 mm;
// bone from 43 mm. At 20 mm/s and 1 kHz a tick is 0.02 mm.
TEST(Scenes, LumbarPunctureTableDepths)
{
    const SceneRun r = simulate("lumbar-puncture");
    const double t = tick("lumbar-puncture");
    // Depths are sums of ticks: a boundary is met within one tick (plus round-off).
    EXPECT_NEAR(first(r, EventType::SkinEntry), 2.0, t + 1e-9);
    EXPECT_NEAR(first(r, EventType::DuraPuncture), 30.0, t + 1e-9);
    EXPECT_NEAR(first(r, EventType::BoneContact), 43.0, t + 1e-9);
    EXPECT_EQ(r.result.summary.pops, 3); // skin, ligament, dura: each layer's k·x drops at its end
    // Bone k·x at 49.99 mm (§4's 16.568 N), within a tick, plus the scene's bone texture
    // c = 0.3 N (§4 [chosen]) while the tip moves in bone.
    EXPECT_NEAR(r.result.summary.peakModelN, 16.568 + 0.3, 0.02 * 2.37 + 5e-4);
}

// Kyung on the torso: the needle stops on the first cortical bone of the analytic
// model (volume::traceLayers on the classifier, not the voxels); on an oblique path a
// voxelised boundary moves by at most a voxel diagonal.
TEST(Scenes, KyungBoneContactWhereTheModelHasBone)
{
    const SceneInstance& inst = instance("kyung");
    const volume::PhantomModel m = volume::torsoModel({}, table());
    const Vec3d dir = (inst.target() - inst.entry()).normalized();
    double bone = kNoLimit;
    for (const volume::LayerSpan& s : volume::traceLayers(m.classify, inst.entry(), dir, 100.0, table(), 0.01)) {
        if (table().at(s.tissue).rigid) {
            bone = s.startMm;
            break;
        }
    }
    ASSERT_TRUE(std::isfinite(bone));
    const SceneRun r = simulate("kyung");
    EXPECT_NEAR(first(r, EventType::BoneContact), bone, std::sqrt(3.0) * kVoxelMm + 0.01);
    EXPECT_EQ(r.result.summary.breaches, 0);
    EXPECT_EQ(r.result.summary.faults, 0);
    // Rendered force never above the PHANToM's 8.5 N peak (§1.1).
    EXPECT_LE(r.result.summary.peakRenderedN, 8.5 + 1e-9);
}

// Only what the terms read is built: a fixed-table scene without voxel damping has no
// damping grid; Kyung has one.
TEST(Scenes, OnlyNeededGridsAreBuilt)
{
    const SceneInstance& lp = instance("lumbar-puncture");
    ASSERT_NE(lp.field(), nullptr); // labels, for the critical-structure rule
    EXPECT_EQ(lp.field()->damping(), nullptr);
    EXPECT_EQ(lp.field()->boneStiffness(), nullptr);
    const SceneInstance& k = instance("kyung");
    EXPECT_NE(k.field()->damping(), nullptr);
}

TEST(Scenes, BadScenesNameFileAndField)
{
    const auto message = [](const std::string& json) {
        try {
            parseScene(json, "bad.json");
        } catch (const ValueError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    const std::string head = R"({"schema": "voxhap-scene/1", "name": "x", "model": "senac", )";
    EXPECT_NE(message("{").find("bad.json: not valid JSON"), std::string::npos);
    EXPECT_NE(message(head + R"("terms": {"tip": true}, "colour": 1})").find("bad.json: colour: unknown field"),
        std::string::npos);
    EXPECT_NE(message(head + R"("terms": {"lor": {"time_constant_ms": -1}}})")
                  .find("terms.lor.time_constant_ms: must be in (0, 10000] ms (got -1)"),
        std::string::npos);
    EXPECT_NE(
        message(head + R"("terms": {}, "needle": {"gauge": 40}})").find("needle: needle: gauge 40 outside 14..27"),
        std::string::npos);
    EXPECT_NE(message(R"({"schema": "voxhap-scene/1", "name": "x", "model": "magic", "terms": {}})")
                  .find("model: unknown force model"),
        std::string::npos);
    EXPECT_NE(
        message(R"({"schema": "voxhap-scene/1", "name": "x", "model": "senac"})").find("bad.json: terms: missing"),
        std::string::npos);
    EXPECT_NE(message(head + R"("terms": {}, "overrides": {"dura": {"puncture_force_N": "8"}}})")
                  .find("overrides.dura.puncture_force_N: must be a finite number"),
        std::string::npos);
    EXPECT_THROW(loadScene("no-such-scene"), IoError);
}

} // namespace
} // namespace voxhap::haptic

namespace voxhap::haptic {
namespace {

// After skin entry the Kyung model reads damping from the trajectory profile (O(1) per
// tick); on the locked line the profile is exact, so the force equals the one from the
// exact voxel traversal, tick for tick (to round-off of the cumulative sums).
TEST(Scenes, LockedProfileMatchesExactTraversal)
{
    const SceneInstance& inst = instance("kyung");
    const Scene& scene = inst.scene();
    auto withProfile = inst.makeModel();
    IntegratorOptions o;
    o.trackLabels = true;
    NeedleForceModel exact(ForceModelSetup{.layers = inst.layers(),
        .path = withProfile->path(),
        .terms = scene.terms,
        .needle = scene.needle,
        .device = scene.device,
        .integrator = makeIntegrator(*inst.field(), o),
        .field = inst.field()});
    const double depth = (inst.target() - inst.entry()).norm();
    const InsertionScript script = InsertionScript::constantSpeed(-5.0, depth, 10.0);
    const InsertionResult a = runInsertion(*withProfile, script, 1000.0);
    const InsertionResult b = runInsertion(exact, script, 1000.0);
    ASSERT_EQ(a.rows.size(), b.rows.size());
    double worst = 0.0;
    for (std::size_t i = 0; i < a.rows.size(); ++i)
        worst = std::max(worst, std::abs(a.rows[i].axialN - b.rows[i].axialN));
    EXPECT_LT(worst, 1e-9);               // N: cumulative-sum round-off over ~100 mm of 0.5 mm voxels
    EXPECT_GT(a.summary.peakModelN, 0.1); // and there was damping to compare
}

// Issue: a script turns the needle at a depth, and the run reports the bent tip's
// deviation from the straight line (physics.md §9.3, §9.6). A half turn at 25 mm
// steers the 22 G Quincke needle back: the tip ends nearer the line than without it.
TEST(Scenes, AScriptTurnsTheBendingNeedleAndTheRunReportsTheTipsDeviation)
{
    const std::filesystem::path dir = std::filesystem::path(testing::TempDir()) / "voxhap-roll-script";
    std::filesystem::create_directories(dir);
    const auto write = [&](const std::string& name, const std::string& text) {
        std::ofstream(dir / name) << text;
        return dir / name;
    };
    // 20 mm/s from 5 mm outside to 45 mm; the half turn over 0.1 s at 25 mm.
    const InsertionScript turned =
        InsertionScript::load(write("turn.csv", "t_s,depth_mm,roll_deg\n0,-5,0\n1.5,25,0\n1.6,25,180\n2.6,45,180\n"));
    const InsertionScript straightOn =
        InsertionScript::load(write("straight.csv", "t_s,depth_mm\n0,-5\n1.5,25\n1.6,25\n2.6,45\n"));
    EXPECT_TRUE(std::isnan(straightOn.rollAt(1.0)));
    EXPECT_NEAR(turned.rollAt(1.55), kPi / 2.0, 1e-12);

    const SceneInstance& inst = instance("lumbar-puncture-bending");
    const auto deviation = [&](const InsertionScript& script) {
        auto model = inst.makeModel();
        const InsertionResult r = runInsertion(*model, script, 1000.0);
        EXPECT_TRUE(r.summary.bending);
        EXPECT_GE(r.summary.maxTipDeviationMm, r.summary.tipDeviationMm);
        // The summary's figure is the bent tip's distance from the path's line.
        const Vec3d off = model->bentNeedle()->tip() - model->path().origin;
        const Vec3d& u = model->path().direction;
        EXPECT_NEAR(r.summary.tipDeviationMm, (off - off.dot(u) * u).norm(), 1e-12);
        EXPECT_NE(insertionSummaryText(r, inst.layers()).find("tip deviation"), std::string::npos);
        return r.summary.tipDeviationMm;
    };
    const double without = deviation(straightOn), with = deviation(turned);
    EXPECT_GT(without, 1.0) << "the bevel takes the tip off the line";
    EXPECT_LT(with, without - 0.5) << "the half turn steers it back";

    // A straight needle reports none (control: the figure belongs to bending).
    auto straightModel = instance("lumbar-puncture").makeModel();
    const InsertionResult plain = runInsertion(*straightModel, straightOn, 1000.0);
    EXPECT_FALSE(plain.summary.bending);
    EXPECT_EQ(
        insertionSummaryText(plain, instance("lumbar-puncture").layers()).find("tip deviation"), std::string::npos);

    // Every row has the roll, or none has.
    const auto refused = [&](const std::string& name, const std::string& text, const std::string& what) {
        try {
            (void)InsertionScript::load(write(name, text));
        } catch (const ValueError& e) {
            return std::string(e.what()).find(what) != std::string::npos;
        }
        return false;
    };
    EXPECT_TRUE(refused("mixed.csv", "0,0,0\n1,10\n", "line 2: expected \"t_s,depth_mm,roll_deg\""));
    EXPECT_TRUE(refused("extra.csv", "0,0\n1,10,90\n", "line 2: expected \"t_s,depth_mm\""));
    EXPECT_TRUE(refused("nan.csv", "0,0,0\n1,10,nan\n", "line 2"));
    EXPECT_FALSE(refused("fine.csv", "0,0,0\n1,10,90\n", "line")) << "control";
}

} // namespace
} // namespace voxhap::haptic
