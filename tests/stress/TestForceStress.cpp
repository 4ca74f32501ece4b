// SPDX-License-Identifier: Apache-2.0
/// @file TestForceStress.cpp
/// @brief The force pipeline under physics.md §6.4: random and hostile states,
/// dt jitter, passivity of closed loops, the critical-structure rule, and no
/// allocation or release of any kind per tick (AllocationCounter.h), with the
/// record queue draining or full.

#include "common/BuiltinTable.h"
#include "common/Phantom.h"
#include "stress/AllocationCounter.h"

#include "haptic/models/LayerTables.h"
#include "haptic/force/NeedleForceModel.h"
#include "haptic/scene/Scene.h"
#include "haptic/servo/ServoLoop.h"
#include "haptic/servo/SimulatedDevices.h"
#include "volume/Grids.h"

#include <Eigen/Geometry> // for cross and unitOrthogonal
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <random>

namespace voxhap::haptic {
namespace {

using voxhap::test::table;

const SceneInstance& instance(const std::string& name)
{
    static std::map<std::string, std::unique_ptr<SceneInstance>> cache;
    auto& slot = cache[name];
    if (!slot) slot = std::make_unique<SceneInstance>(loadScene(name), nullptr, table());
    return *slot;
}

/// §6.4 "NaN/Inf", "extreme velocity", "dt jitter": 10⁶ random states, a tenth of them
/// hostile. Every output is finite and within the device's peak; a non-finite input
/// latches the fault and the force stays exactly zero until reset.
void fuzz(const std::string& scene, long states, unsigned seed)
{
    const SceneInstance& inst = instance(scene);
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

TEST(ForceStress, MillionRandomStatesSenac) { fuzz("senac-average", 1000000, 1); }
TEST(ForceStress, RandomStatesKyungWithDampingPivotAndBone) { fuzz("kyung", 200000, 2); }

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

// The servo tick: device read, model, watchdog, write, queues and statistics allocate nothing.
TEST(ForceStress, ServoTickNeverAllocates)
{
    const SceneInstance& inst = instance("senac-average");
    auto model = inst.makeModel();
    HandParams p;
    p.speedMmPerS = 10.0;
    p.stopOnLor = false;
    HandDevice hand(model->path(), p, model->device());
    ServoLoop loop(*model, hand);
    loop.runTicks(10); // first touches
    const long before = test::allocations(), freesBefore = test::deallocations();
    loop.runTicks(8000); // through skin, ligaments, LOR and dura
    EXPECT_EQ(test::allocations() - before, 0);
    EXPECT_EQ(test::deallocations() - freesBefore, 0);
    Event e;
    bool dura = false;
    while (loop.popEvent(e)) dura = dura || e.type == EventType::DuraPuncture;
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

/// Work done on the hand: the force held over each tick times the device point's
/// displacement, Σ F_n·(x_{n+1} − x_n) (zero-order hold, the sampled-data truth).
class EnergyMeter {
public:
    EnergyMeter(NeedleForceModel& m, double rateHz) : mModel(m), mDt(1.0 / rateHz) { }
    void move(const Vec3d& tip, const Vec3d& dir)
    {
        const Vec3d hub = tip - mModel.needle().lengthMm * dir;
        if (mHave) mEnergyNmm += mLastForce.dot(hub - mLastHub);
        NeedleInput in;
        in.timeS = mT;
        in.dtS = mDt;
        in.tip = tip;
        in.direction = dir;
        in.velocity = mHave ? Vec3d((tip - mLastTip) / mDt) : Vec3d::Zero();
        mModel.step(in, mOut);
        mLastForce = mOut.force;
        mLastHub = hub;
        mLastTip = tip;
        mHave = true;
        mT += mDt;
    }
    double joules() const { return mEnergyNmm * 1e-3; }
    const NeedleOutput& out() const { return mOut; }

private:
    NeedleForceModel& mModel;
    double mDt, mT = 0.0, mEnergyNmm = 0.0;
    bool mHave = false;
    Vec3d mLastForce = Vec3d::Zero(), mLastHub = Vec3d::Zero(), mLastTip = Vec3d::Zero();
    NeedleOutput mOut;
};

/// §6.4 passivity: closed loops create no energy, Σ F·Δx <= 1e-6 J. The stored
/// energy of tenting and the contact springs is what a sampled spring leaks; the
/// passivity controller (Safety.h) must take it back.
constexpr double kPassivityJ = 1e-6;

TEST(Passivity, InsertRetractLoops)
{
    const SceneInstance& inst = instance("senac-average");
    const Vec3d e = inst.entry(), u = (inst.target() - inst.entry()).normalized();
    for (const double depth : {5.0, 9.9, 20.0, 45.0}) { // tenting only, just before the pop, cutting, dura
        for (const double speed : {2.0, 20.0, 200.0}) {
            auto model = inst.makeModel();
            EnergyMeter m(*model, 1000.0);
            const double step = speed * 1e-3;
            for (int loop = 0; loop < 3; ++loop) {
                for (double d = -5.0; d < depth; d += step) m.move(e + d * u, u);
                for (double d = depth; d > -5.0; d -= step) m.move(e + d * u, u);
            }
            m.move(e - 5.0 * u, u);
            EXPECT_LE(m.joules(), kPassivityJ) << "depth " << depth << " speed " << speed;
        }
    }
}

TEST(Passivity, LateralCirclesAfterSkinEntry)
{
    for (const char* scene : {"senac-average", "kyung"}) { // the trajectory lock; the Kelvin pivot
        const SceneInstance& inst = instance(scene);
        const Vec3d e = inst.entry(), u = (inst.target() - inst.entry()).normalized();
        const Vec3d a = u.unitOrthogonal(), b = u.cross(a);
        auto model = inst.makeModel();
        EnergyMeter m(*model, 1000.0);
        for (double d = -5.0; d < 25.0; d += 0.01) m.move(e + d * u, u);
        // Tilt about the skin entry by 5° and go round three times, then come back.
        const double tilt = 5.0 * kPi / 180.0;
        for (int i = 0; i <= 3000; ++i) {
            const double phi = 2.0 * kPi * i / 1000.0;
            const double th = tilt * std::min(1.0, std::min(i, 3000 - i) / 100.0);
            const Vec3d dir = (std::cos(th) * u + std::sin(th) * (std::cos(phi) * a + std::sin(phi) * b)).normalized();
            m.move(e + 25.0 * dir, dir);
            // R7 in the pipeline: the Kelvin correction stays within [K01]'s 2 N (§1.4).
            if (std::string(scene) == "kyung") {
                EXPECT_LE(m.out().terms.lateral.norm(), 2.0 + 1e-12);
            }
        }
        // Then sideways translations in a square, which the lock resists.
        const Vec3d c = e + 25.0 * u;
        for (int i = 0; i <= 4000; ++i) {
            const double s = (i % 1000) / 1000.0 * 2.0;
            const int side = i / 1000 % 4;
            const Vec3d corner[4] = {Vec3d::Zero(), 2.0 * a, 2.0 * (a + b), 2.0 * b};
            const Vec3d off = corner[side] + 0.5 * s * (corner[(side + 1) % 4] - corner[side]);
            m.move(c + off, u);
        }
        for (double d = 25.0; d > -5.0; d -= 0.01) m.move(e + d * u, u);
        EXPECT_LE(m.joules(), kPassivityJ) << scene;
    }
}

TEST(Passivity, RandomWalkReturningHome)
{
    const SceneInstance& inst = instance("lumbar-puncture");
    const Vec3d e = inst.entry(), u = (inst.target() - inst.entry()).normalized();
    std::mt19937 rng(7);
    std::normal_distribution<double> g(0.0, 1.0);
    auto model = inst.makeModel();
    EnergyMeter m(*model, 1000.0);
    double d = -5.0;
    for (int i = 0; i < 50000; ++i) {
        d = std::clamp(d + 0.02 * g(rng) + 0.001, -5.0, 48.0);
        m.move(e + d * u, u);
    }
    for (; d > -5.0; d -= 0.02) m.move(e + d * u, u);
    EXPECT_LE(m.joules(), kPassivityJ);
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
