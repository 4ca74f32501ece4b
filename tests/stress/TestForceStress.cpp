// SPDX-License-Identifier: Apache-2.0
/// @file TestForceStress.cpp
/// @brief The force pipeline under physics.md §6.4: random and hostile states,
/// dt jitter, the critical-structure rule, and no
/// allocation or release of any kind per tick (AllocationCounter.h), with the
/// record queue draining or full.

#include "common/BuiltinTable.h"
#include "common/Phantom.h"
#include "common/SceneCache.h"
#include "stress/AllocationCounter.h"

#include "haptic/devices/SimulatedDevices.h"
#include "haptic/force/NeedleForceModel.h"
#include "haptic/papers/LayerTables.h"
#include "haptic/scene/Scene.h"
#include "haptic/servo/ServoLoop.h"
#include "haptic/servo/ServoStep.h"
#include "volume/Grids.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <random>

namespace voxhap::haptic {
namespace {

using voxhap::test::table;

const SceneInstance& instance(const std::string& name) { return test::sceneInstance(name); }

/// §6.4 "NaN/Inf", "extreme velocity", "dt jitter": 10⁶ random states, a tenth of them
/// hostile. Every output is finite and within the device's peak; a non-finite input
/// latches the fault and the force stays exactly zero until reset.
void fuzz(const SceneInstance& inst, long states, unsigned seed)
{
    auto model = inst.makeModel();
    const double peak = inst.scene().device.maxForceN;
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    const double dts[] = {0.0, 1e-6, 0.5e-3, 1e-3, 2e-3, 1e-2, 1.0, nan, -1.0, inf};
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::uniform_int_distribution<int> pick(0, 99);
    const Vec3d entry = inst.entry(), dir = (inst.target() - inst.entry()).normalized();
    NeedleOutput out;
    double t = 0.0;
    long faults = 0;
    for (long n = 0; n < states; ++n) {
        NeedleInput in;
        const int kind = pick(rng);
        in.dtS = dts[std::size_t(pick(rng)) % std::size(dts)];
        t += std::isfinite(in.dtS) && in.dtS > 0.0 ? in.dtS : 0.0;
        in.timeS = t;
        // Mostly near the path (so that layers, pops and bone are visited), sometimes anywhere.
        const double depth = 60.0 * unit(rng) + 30.0;
        in.tip = entry + depth * dir + Vec3d(unit(rng), unit(rng), unit(rng)) * (kind < 80 ? 2.0 : 200.0);
        in.direction = (dir + 0.2 * Vec3d(unit(rng), unit(rng), unit(rng))).normalized();
        in.velocity = dir * (kind < 90 ? 50.0 * unit(rng) : 1e4 * unit(rng)); // up to 10 m/s
        if (kind == 95) in.tip += Vec3d(1000.0, 0.0, 0.0);                    // a 1 m jump in one tick
        if (kind == 96) in.tip.x() = nan;
        if (kind == 97) in.velocity.y() = inf;
        if (kind == 98) in.direction = Vec3d::Zero();
        if (kind == 99) in.tip.z() = std::numeric_limits<double>::denorm_min();
        model->step(in, out);
        ASSERT_TRUE(out.force.allFinite()) << "state " << n;
        ASSERT_LE(out.force.norm(), peak * (1.0 + 1e-12)) << "state " << n;
        if (out.fault) {
            ++faults;
            ASSERT_EQ(out.force, Vec3d::Zero());
            in.tip = entry; // a good reading does not clear a latched fault
            in.direction = dir;
            in.velocity = Vec3d::Zero();
            in.timeS = t;
            model->step(in, out);
            ASSERT_TRUE(out.fault);
            ASSERT_EQ(out.force, Vec3d::Zero());
            model->reset();
        }
    }
    EXPECT_GT(faults, states / 200); // kinds 96–98 are non-finite or degenerate: about 3 %
}

TEST(ForceStress, MillionRandomStatesSenac) { fuzz(instance("senac-average"), 1000000, 1); }
TEST(ForceStress, RandomStatesKyungWithDampingPivotAndBone) { fuzz(instance("kyung"), 200000, 2); }

/// senac-average with palpation (issue 23 item 1) and guidance toward a line 2 mm
/// beside the path (item 2) on.
const SceneInstance& palpationInstance()
{
    static const SceneInstance inst = [] {
        std::ifstream in(VOXHAP_SOURCE_DIR "/data/scenes/senac-average.json");
        nlohmann::json j = nlohmann::json::parse(in);
        j["terms"]["palpation"] = {{"entry_radius_mm", 1.0}, {"radius_mm", 30.0}};
        j["terms"]["guidance"] = {{"stiffness_N_per_mm", 0.2}, {"fade_out_s", 30.0}};
        return SceneInstance(parseScene(j.dump(), "stress.json"), nullptr, table());
    }();
    return inst;
}

TEST(ForceStress, RandomStatesWithPalpationAndGuidance) { fuzz(palpationInstance(), 200000, 3); }

// Palpating (contact, friction, the proxy's descent), the hand-over to the needle and
// the insertion with guidance on: no allocation or release in any tick.
TEST(ForceStress, PalpationAndGuidanceStepNeverAllocates)
{
    const SceneInstance& inst = palpationInstance();
    auto model = inst.makeModel(GuideLine{inst.entry() + Vec3d(2.0, 0.0, 0.0), inst.target() + Vec3d(2.0, 0.0, 0.0)});
    const Vec3d dir = (inst.target() - inst.entry()).normalized();
    NeedleOutput out;
    NeedleInput in;
    in.direction = dir;
    long n = 0, palpating = 0, contact = 0;
    bool entered = false;
    const auto at = [&](const Vec3d& tip) {
        in.timeS = 1e-3 * double(n++);
        in.tip = tip;
        model->step(in, out);
        palpating += out.palpating;
        contact += out.palpation.contact;
        for (const Event& e : out.events) entered = entered || e.type == EventType::SkinEntry;
    };
    const Vec3d up = -3.0 * dir;
    at(inst.entry() + Vec3d(0.0, 0.0, 20.0) + up); // the first tick may set things up
    const long before = test::allocations(), freesBefore = test::deallocations();
    for (int i = 0; i <= 1000; ++i) at(inst.entry() + Vec3d(0.0, 0.0, 20.0) + up + 0.006 * i * dir); // press in
    for (int i = 0; i <= 4000; ++i) // slide across processes and the interspace, in contact
        at(inst.entry() + Vec3d(3.0 * std::sin(0.01 * i), 0.0, 20.0 - 0.01 * i) + 3.0 * dir);
    for (int i = 0; i <= 1000; ++i) at(inst.entry() + Vec3d(0.0, 0.0, -20.0) + 3.0 * dir - 0.006 * i * dir); // lift
    for (int i = 0; i <= 1000; ++i) at(inst.entry() + (-20.0 + 0.02 * i) * Vec3d(0.0, 0.0, 1.0) + up); // to the entry
    for (int i = 0; i <= 6000; ++i) at(inst.entry() + up + 0.004 * i * dir);                           // insert
    EXPECT_EQ(test::allocations() - before, 0);
    EXPECT_EQ(test::deallocations() - freesBefore, 0);
    EXPECT_GT(palpating, 5000);
    EXPECT_GT(contact, 4000);
    EXPECT_TRUE(entered);
}

TEST(ForceStress, StepNeverAllocates)
{
    const SceneInstance& inst = instance("senac-average");
    auto model = inst.makeModel();
    const Vec3d entry = inst.entry(), dir = (inst.target() - inst.entry()).normalized();
    NeedleOutput out;
    NeedleInput in;
    in.direction = dir;
    in.velocity = 5.0 * dir;
    const long before = test::allocations(), freesBefore = test::deallocations();
    for (int n = 0; n < 20000; ++n) { // in to 45 mm (pops, LOR, dura) and out again
        const double d = n < 10000 ? -5.0 + 0.005 * n : 45.0 - 0.005 * (n - 10000);
        in.timeS = 1e-3 * n;
        in.tip = entry + d * dir + Vec3d(0.3 * std::sin(0.01 * n), 0.0, 0.0);
        in.velocity = (n < 10000 ? 5.0 : -5.0) * dir;
        model->step(in, out);
    }
    EXPECT_EQ(test::allocations() - before, 0);
    EXPECT_EQ(test::deallocations() - freesBefore, 0);
}

/// A simulated hand at 10 mm/s through @p scene in a ServoLoop: @p ticks ticks after
/// the first ten (first touches) make no allocation and free nothing; then @p after
/// looks at the loop.
template <typename After> void servoTicksAllocateNothing(const std::string& scene, long ticks, After&& after)
{
    const SceneInstance& inst = instance(scene);
    auto model = inst.makeModel();
    HandParams p;
    p.speedMmPerS = 10.0;
    p.stopOnLor = false;
    HandDevice hand(model->path(), p, model->device());
    ServoLoop loop(*model, hand);
    loop.runTicks(10);
    const long before = test::allocations(), freesBefore = test::deallocations();
    loop.runTicks(ticks);
    EXPECT_EQ(test::allocations() - before, 0) << scene;
    EXPECT_EQ(test::deallocations() - freesBefore, 0) << scene;
    after(loop);
}

// The servo tick: device read, model, watchdog, write, queues and statistics allocate nothing.
TEST(ForceStress, ServoTickNeverAllocates)
{
    servoTicksAllocateNothing("senac-average", 8000, [](ServoLoop& loop) { // through skin, ligaments, LOR and dura
        Event e;
        bool dura = false;
        while (loop.popEvent(e)) dura = dura || e.type == EventType::DuraPuncture;
        EXPECT_TRUE(dura); // the ticks did go through the interesting states
    });
}

// ... and with a needle that bends: the beam's solve, the bent shaft and the shaft's
// publication for a viewer (ServoLoop::shaft, a sequence lock over preallocated
// atomics) allocate nothing either.
TEST(ForceStress, ServoTickOfABendingNeedleNeverAllocates)
{
    servoTicksAllocateNothing("lumbar-puncture-bending", 5000, [](ServoLoop& loop) { // skin and ligaments, bending
        std::vector<Vec3d> shaft;
        EXPECT_EQ(loop.shaft().read(shaft), 501u) << "a publication every 10 ticks, the first at tick 0";
        EXPECT_GE(shaft.size(), 2u);
    });
}

// The tick in a caller's own loop (a device SDK's callback, examples/device-loop/):
// ServoStep's step from the caller's times, reading and writing the caller's device,
// allocates nothing either.
TEST(ForceStress, ServoStepInTheCallersLoopNeverAllocates)
{
    const SceneInstance& inst = instance("senac-average");
    auto model = inst.makeModel();
    HandParams p;
    p.speedMmPerS = 10.0;
    p.stopOnLor = false;
    HandDevice hand(model->path(), p, model->device());
    ServoStep servo(*model);
    double t = 0.0;
    bool dura = false;
    auto tick = [&] {
        const Vec3d f = servo.step(hand.read(t), t);
        for (const Event& e : servo.output().events) dura = dura || e.type == EventType::DuraPuncture;
        hand.write(f, servo.output().plungerN, t);
        t += 1e-3;
    };
    for (int k = 0; k < 10; ++k) tick(); // first touches
    const long before = test::allocations(), freesBefore = test::deallocations();
    for (int k = 0; k < 8000; ++k) tick(); // through skin, ligaments, LOR and dura
    EXPECT_EQ(test::allocations() - before, 0);
    EXPECT_EQ(test::deallocations() - freesBefore, 0);
    EXPECT_TRUE(dura); // the ticks did go through the interesting states
}

// The same with the record queue full because nobody drains it: a dropped record
// costs no allocation either, the tick goes on, and every drop is counted.
TEST(ForceStress, ServoTickWithAFullRecordQueueNeverAllocates)
{
    const SceneInstance& inst = instance("senac-average");
    auto model = inst.makeModel();
    HandParams p;
    p.speedMmPerS = 1.0; // 65 mm in the 65 s that fill the queue
    p.stopOnLor = false;
    HandDevice hand(model->path(), p, model->device());
    ServoLoop loop(*model, hand);
    constexpr long kRecordCapacity = 1L << 16; // 65 s at 1 kHz (ServoLoop.h)
    loop.runTicks(kRecordCapacity);
    ASSERT_EQ(loop.droppedRecords(), 0);
    const long before = test::allocations(), freesBefore = test::deallocations();
    loop.runTicks(8000);
    EXPECT_EQ(test::allocations() - before, 0);
    EXPECT_EQ(test::deallocations() - freesBefore, 0);
    EXPECT_EQ(loop.ticks(), kRecordCapacity + 8000);
    EXPECT_EQ(loop.droppedRecords(), 8000);
}

/// §1.1 and §6.4 "safety labels": one lung voxel on the path zeroes the force and
/// raises the warning in the same tick; retracting off it restores the force.
TEST(CriticalStructures, OneLungVoxelZeroesForceWithinOneTick)
{
    // A 1 mm fat block with one lung voxel at (0, 0, 10) on the path x = y = 0.
    auto labels = volume::LabelGrid::create(0);
    labels->setTransform(openvdb::math::Transform::createLinearTransform(1.0));
    const int fat = table().at("fat").id, lung = table().at("lung").id;
    labels->tree().fill(openvdb::CoordBBox(openvdb::Coord(-5, -5, 0), openvdb::Coord(5, 5, 30)), fat);
    labels->tree().setValue(openvdb::Coord(0, 0, 10), lung);
    auto beta = test::betaFromLabels(*labels, test::testBeta());
    const MaterialField field(beta, labels, table());
    LayerRecipe recipe;
    recipe.model = LayerModel::Kyung;
    const Vec3d entry(0.0, 0.0, -0.5), dir(0.0, 0.0, 1.0); // the block's surface is the face z = -0.5
    ForceTerms terms;
    terms.tip = terms.cutting = terms.viscous = false;
    terms.damping.on = true;
    terms.critical = true;
    IntegratorOptions io;
    io.trackLabels = true;
    DeviceLimits dev;
    dev.maxForceN = dev.maxContinuousForceN = 100.0;
    NeedleForceModel model(
        ForceModelSetup{.layers = layersFromRuns(traceLabelRuns(field, entry, dir, 40.0), table(), recipe),
            .path = NeedlePath{entry, dir},
            .terms = terms,
            .needle = Needle{},
            .device = dev,
            .integrator = makeIntegrator(field, io),
            .field = &field});
    NeedleOutput out;
    double breachDepth = kNoLimit;
    const double lungFace = 9.5 + 0.5; // depth of the voxel's face z = 9.5 from the entry z = -0.5
    for (int n = 1; n <= 2000; ++n) {
        const double d = 0.01 * n; // 0.01 mm per tick
        NeedleInput in;
        in.timeS = 1e-3 * n;
        in.tip = entry + d * dir;
        in.direction = dir;
        in.velocity = 10.0 * dir;
        model.step(in, out);
        for (const Event& e : out.events) {
            if (e.type == EventType::CriticalBreach && !std::isfinite(breachDepth)) breachDepth = d;
        }
        if (d < lungFace - 1e-9) {
            EXPECT_GT(out.force.norm(), 0.0) << "before the lung at " << d;
        } else if (d > lungFace + 1e-9) {
            EXPECT_EQ(out.force, Vec3d::Zero()) << "in or past the lung at " << d; // the shaft still touches it
            EXPECT_TRUE(out.critical);
        }
    }
    // The warning comes with the tick that reaches the voxel (the face itself counts).
    EXPECT_GE(breachDepth, lungFace - 1e-9);
    EXPECT_LE(breachDepth, lungFace + 0.01 + 1e-9);
    const bool breached = std::isfinite(breachDepth);
    EXPECT_TRUE(breached);
    // Pull back out of the lung voxel: the warning clears and the force returns.
    NeedleInput in;
    in.timeS = 3.0;
    in.tip = entry + 5.0 * dir;
    in.direction = dir;
    in.velocity = 10.0 * dir;
    model.step(in, out);
    bool cleared = false;
    for (const Event& e : out.events) cleared = cleared || e.type == EventType::CriticalClear;
    EXPECT_TRUE(cleared);
    EXPECT_GT(out.force.norm(), 0.0);
}

} // namespace
} // namespace voxhap::haptic
