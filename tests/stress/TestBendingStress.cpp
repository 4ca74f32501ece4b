// SPDX-License-Identifier: Apache-2.0
/// @file TestBendingStress.cpp
/// @brief The bending needle under physics.md §6.4 and §9.4: stiff beams, a very
/// soft foundation, a zero-length shaft in tissue, a needle turned at every tick,
/// a pop while bent and hostile poses give finite forces within the caps; the
/// solve and the bent tick allocate nothing.

#include "common/BuiltinTable.h"
#include "common/SceneCache.h"
#include "stress/AllocationCounter.h"

#include "haptic/beam/BentNeedle.h"
#include "haptic/scene/Scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace voxhap::haptic {
namespace {

using voxhap::test::table;

/// Bounds every output of one bent solve must keep: finite, and the bevel force
/// within the stiffest tissue's k times the bevel's factor.
void expectSane(const BentNeedle& b, double kMax, const char* what)
{
    for (const Vec3d& p : b.shaft()) ASSERT_TRUE(p.allFinite()) << what;
    ASSERT_TRUE(b.tipDirection().allFinite()) << what;
    ASSERT_TRUE(b.hubForce().allFinite() && b.hubTorque().allFinite()) << what;
    ASSERT_LE(b.bevelForce().norm(), kMax * b.params().bevelFactorMm2 * (1.0 + 1e-12)) << what;
}

/// Insert @p depth mm along +z into uniform tissue k, turning to @p roll(i) each step.
template <typename Roll> BentNeedle insert(const Needle& n, double k, double depth, Roll&& roll)
{
    BentNeedle b(BeamParams::fromNeedle(n), std::make_unique<UniformFoundation>(k), Vec3d::UnitX());
    double hub = -n.lengthMm;
    b.update(Vec3d(0, 0, hub), Vec3d::UnitZ());
    b.enter(Vec3d::Zero());
    const int steps = int(std::ceil(depth / 0.05));
    for (int i = 0; i < steps; ++i) {
        hub += depth / steps;
        b.setRoll(roll(i));
        EXPECT_TRUE(b.update(Vec3d(0, 0, hub), Vec3d::UnitZ()));
        expectSane(b, k, "insertion");
    }
    return b;
}

Needle needle(int gauge, double length)
{
    Needle n;
    n.gauge = gauge;
    n.lengthMm = length;
    return n;
}

TEST(BendingStress, StiffBeamsSoftAndStiffFoundationsStayFinite)
{
    const auto still = [](int) { return 0.0; };
    Needle stiff = needle(14, 150.0);
    stiff.youngsModulusMPa = 1e6; // 1000 GPa, the scene's largest
    stiff.stylet = true;
    BentNeedle a = insert(stiff, 1e-9, 100.0, still); // λh ~ 1e-4: the bending dominates
    EXPECT_LT(a.tipDeflectionMm(), 1e-6);
    // The table's stiffest k on the thinnest needle: a bevel force of 2 kN and a
    // steady curvature of 5 /mm, far outside small slopes: held at the steepest
    // slope the theory is followed to, the tip within that slope of the hub's axis.
    BentNeedle b = insert(needle(27, 150.0), 1e4, 100.0, still);
    EXPECT_TRUE(b.slopeLimited());
    EXPECT_LE(b.tipDeflectionMm(), 150.0 * BentNeedle::kMaxSlope + 1e-9);
    for (int i = 1; i < b.nodes(); ++i) { // each element keeps its length
        const double h = (b.shaft()[std::size_t(i)] - b.shaft()[std::size_t(i - 1)]).norm();
        EXPECT_NEAR(h, 150.0 / (b.nodes() - 1), 1e-9);
    }
    BentNeedle c = insert(needle(27, 150.0), 1e-12, 100.0, still); // nearly no tissue: a cantilever
    EXPECT_LT(c.tipDeflectionMm(), 1e-6);
}

TEST(BendingStress, ZeroLengthShaftInTissue)
{
    for (const double length : {1e-9, 1e-3, 0.5}) {
        const auto still = [](int) { return 0.0; };
        BentNeedle b = insert(needle(22, length), 1.0, 0.9 * length, still);
        EXPECT_LT(b.tipDeflectionMm(), length);
    }
    // The tip just at the skin: nothing inserted, a straight needle.
    Needle n = needle(22, 90.0);
    BentNeedle b(BeamParams::fromNeedle(n), std::make_unique<UniformFoundation>(1.0), Vec3d::UnitX());
    b.update(Vec3d(0, 0, -90.0), Vec3d::UnitZ());
    b.enter(Vec3d::Zero());
    ASSERT_TRUE(b.update(Vec3d(0, 0, -90.0), Vec3d::UnitZ()));
    EXPECT_EQ(b.insertedMm(), 0.0);
    EXPECT_EQ(b.tipDeflectionMm(), 0.0);
}

TEST(BendingStress, TurnedAtEveryTick)
{
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> angle(-10.0, 10.0);
    BentNeedle b = insert(needle(25, 90.0), 0.5, 80.0, [&](int) { return angle(rng); });
    EXPECT_TRUE(b.tip().allFinite());
    // Spinning fast averages the bevel out: far less deflection than a still bevel (control).
    BentNeedle still = insert(needle(25, 90.0), 0.5, 80.0, [](int) { return 0.0; });
    EXPECT_LT(b.tipDeflectionMm(), 0.5 * still.tipDeflectionMm());
}

TEST(BendingStress, HostilePosesGiveAStraightFiniteNeedle)
{
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    const auto still = [](int) { return 0.0; };
    BentNeedle b = insert(needle(22, 90.0), 0.2, 40.0, still);
    EXPECT_FALSE(b.update(Vec3d(nan, 0, 0), Vec3d::UnitZ()));
    expectSane(b, 0.2, "NaN hub");
    EXPECT_FALSE(b.update(Vec3d(0, 0, -50.0), Vec3d(0, 0, 0)));
    expectSane(b, 0.2, "zero direction");
    EXPECT_FALSE(b.update(Vec3d(0, 0, -50.0), Vec3d(inf, 0, 1)));
    expectSane(b, 0.2, "infinite direction");
    // A 1 m jump sideways and a hub driven past the skin: finite.
    EXPECT_TRUE(b.update(Vec3d(1000.0, 0, -50.0), Vec3d::UnitZ()));
    expectSane(b, 0.2, "1 m jump");
    EXPECT_TRUE(b.update(Vec3d(0, 0, 500.0), Vec3d::UnitZ()));
    expectSane(b, 0.2, "hub below the skin");
    EXPECT_EQ(b.insertedMm(), 90.0);
    b.setRoll(nan); // ignored: the last roll stays
    EXPECT_TRUE(b.update(Vec3d(0, 0, -40.0), Vec3d::UnitZ()));
    expectSane(b, 0.2, "NaN roll");
}

// The bending scenes, random states: the force finite and within the device's peak,
// as §6.4 asks of every scene.
TEST(BendingStress, RandomStatesOfBendingScenesStayWithinThePeak)
{
    for (const char* name : {"lumbar-puncture-bending", "kyung-bending"}) {
        const SceneInstance& inst = test::sceneInstance(name);
        auto model = inst.makeModel();
        ASSERT_NE(model->bentNeedle(), nullptr);
        const double peak = inst.scene().device.maxForceN;
        std::mt19937_64 rng(9);
        std::uniform_real_distribution<double> unit(-1.0, 1.0);
        const Vec3d entry = inst.entry(), dir = (inst.target() - inst.entry()).normalized();
        NeedleOutput out;
        for (long n = 0; n < 50000; ++n) {
            NeedleInput in;
            in.timeS = 1e-3 * double(n);
            in.tip = entry + (60.0 * unit(rng) + 30.0) * dir + 2.0 * Vec3d(unit(rng), unit(rng), unit(rng));
            in.direction = (dir + 0.2 * Vec3d(unit(rng), unit(rng), unit(rng))).normalized();
            in.velocity = 50.0 * unit(rng) * dir;
            model->step(in, out);
            ASSERT_TRUE(out.force.allFinite()) << name << " state " << n;
            ASSERT_LE(out.force.norm(), peak * (1.0 + 1e-12)) << name << " state " << n;
        }
    }
}

// A pop while bent: the lumbar puncture pushed through its ligaments with the hub
// swung 3 mm sideways, so that the shaft is loaded against its track when the
// layers give way. Every tick finite and within the peak; the tick allocates nothing.
TEST(BendingStress, APopWhileBentAndTheBentTickNeverAllocates)
{
    const SceneInstance& inst = test::sceneInstance("lumbar-puncture-bending");
    auto model = inst.makeModel();
    const double peak = inst.scene().device.maxForceN;
    const Vec3d entry = inst.entry(), dir = (inst.target() - inst.entry()).normalized();
    const Vec3d side = dir.unitOrthogonal();
    NeedleOutput out;
    NeedleInput in;
    in.direction = dir;
    int pops = 0, popsBent = 0;
    const auto tick = [&](int n, double depth, double sideMm) {
        in.timeS = 1e-3 * n;
        in.tip = entry + depth * dir + sideMm * side;
        in.velocity = 20.0 * dir;
        model->step(in, out);
        ASSERT_TRUE(out.force.allFinite());
        ASSERT_LE(out.force.norm(), peak * (1.0 + 1e-12));
        for (const Event& e : out.events) {
            if (e.type != EventType::Pop) continue;
            ++pops;
            popsBent += model->bentNeedle()->tipDeflectionMm() > 0.05;
        }
    };
    tick(0, -5.0, 0.0); // the first tick may set things up
    const long before = test::allocations(), freesBefore = test::deallocations();
    for (int n = 1; n <= 3000; ++n) tick(n, -5.0 + 0.018 * n, 3.0 * std::min(1.0, n / 600.0)); // in to 49 mm
    for (int n = 3001; n <= 6000; ++n) tick(n, 49.0 - 0.018 * (n - 3000), 3.0);                // and out
    for (int n = 6001; n <= 7000; ++n) tick(n, -5.0 + 0.02 * (n - 6000), 0.0);                 // in again
    EXPECT_EQ(test::allocations() - before, 0);
    EXPECT_EQ(test::deallocations() - freesBefore, 0);
    EXPECT_GE(pops, 2);
    EXPECT_GE(popsBent, 1) << "the pops did happen with the shaft bent";
}

} // namespace
} // namespace voxhap::haptic
