// SPDX-License-Identifier: Apache-2.0
/// @file TestBendingForceModel.cpp
/// @brief The bending needle inside the force model (physics.md §9.5): the model
/// integrates along the bent shaft and reads the bent tip, so a critical voxel
/// that only the bent needle reaches raises the warning; with bending off, the
/// same insertion never touches it (the control). The terms the beam replaces are
/// refused beside it; the hub's force reaches the hand through a coupling; the
/// device's roll turns the bevel; bone contact pins the tip node.

#include "common/BuiltinTable.h"
#include "common/Phantom.h"

#include "core/Errors.h"
#include "core/Math.h"
#include "haptic/beam/Foundation.h"
#include "haptic/force/NeedleForceModel.h"
#include "haptic/papers/LayerTables.h"
#include "haptic/shaft/LabelTrace.h"
#include "volume/Grids.h"

#include <gtest/gtest.h>

#include <cmath>

namespace voxhap::haptic {
namespace {

using voxhap::test::table;

/// A block of muscle, 1 mm voxels, the needle entering its face z = −0.5 along +z;
/// with @p lung, one lung voxel there; from voxel @p boneFromZ on (when ≥ 0),
/// cortical bone.
struct Block {
    volume::LabelGrid::Ptr labels = volume::LabelGrid::create(0);
    std::unique_ptr<MaterialField> field;
    explicit Block(const std::optional<openvdb::Coord>& lung, int boneFromZ = -1)
    {
        labels->setTransform(openvdb::math::Transform::createLinearTransform(1.0));
        labels->tree().fill(
            openvdb::CoordBBox(openvdb::Coord(-40, -40, 0), openvdb::Coord(40, 40, 100)), table().at("muscle").id);
        if (boneFromZ >= 0)
            labels->tree().fill(openvdb::CoordBBox(openvdb::Coord(-40, -40, boneFromZ), openvdb::Coord(40, 40, 100)),
                table().at("cortical_bone").id);
        if (lung) labels->tree().setValue(*lung, table().at("lung").id);
        field = std::make_unique<MaterialField>(test::betaFromLabels(*labels, test::testBeta()), labels, table());
    }
};

const Vec3d kEntry(0.0, 0.0, -0.5), kDir(0.0, 0.0, 1.0);

std::unique_ptr<NeedleForceModel> model(const Block& b, bool bending, bool bone = true)
{
    LayerRecipe recipe;
    recipe.model = LayerModel::Kyung;
    ForceTerms terms;
    terms.tip = terms.cutting = terms.viscous = false;
    terms.damping.on = true;
    terms.critical = true;
    terms.bending.on = bending;
    terms.bone.on = bone;
    Needle n;
    n.gauge = 22;
    n.lengthMm = 90.0;
    n.stylet = true;
    IntegratorOptions io;
    io.trackLabels = true;
    DeviceLimits dev;
    dev.maxForceN = dev.maxContinuousForceN = 100.0;
    return std::make_unique<NeedleForceModel>(
        ForceModelSetup{.layers = layersFromRuns(traceLabelRuns(*b.field, kEntry, kDir, 100.0), table(), recipe),
            .path = NeedlePath{kEntry, kDir},
            .terms = terms,
            .needle = n,
            .device = dev,
            .integrator = makeIntegrator(*b.field, io),
            .field = b.field.get(),
            .foundation = bending ? makeLabelFoundation(*b.field) : nullptr});
}

/// Insert to @p depth at 10 mm/s, 1 kHz, the device straight along the path;
/// the first depth at which the critical warning came, or NaN.
double insert(NeedleForceModel& m, double depth, Vec3d* bentTip = nullptr)
{
    NeedleOutput out;
    double breach = std::nan("");
    const int ticks = int(depth / 0.01);
    for (int i = 0; i <= ticks; ++i) {
        NeedleInput in;
        in.timeS = 1e-3 * i;
        in.tip = kEntry + (-2.0 + 0.01 * i) * kDir;
        in.direction = kDir;
        in.velocity = 10.0 * kDir;
        m.step(in, out);
        for (const Event& e : out.events) {
            if (e.type == EventType::CriticalBreach && std::isnan(breach)) breach = 0.01 * i - 2.0;
        }
    }
    if (bentTip && m.bentNeedle()) *bentTip = m.bentNeedle()->tip();
    return breach;
}

TEST(BendingForceModel, TheBentShaftMeetsACriticalVoxelTheStraightOneMisses)
{
    // Where the bent tip passes 50 mm in (the bevel pushes it toward +z's
    // reference axis, here +x at orientation 0).
    Vec3d tip;
    {
        const Block plain(std::nullopt);
        auto m = model(plain, true);
        EXPECT_TRUE(std::isnan(insert(*m, 52.0, &tip)));
    }
    const double off = std::hypot(tip.x(), tip.y());
    ASSERT_GT(off, 3.0) << "the needle must leave its line by voxels for this test";
    const openvdb::Coord lung(int(std::lround(tip.x())), int(std::lround(tip.y())), int(std::lround(tip.z())));
    const Block block(lung);
    auto bent = model(block, true);
    const double breach = insert(*bent, 55.0);
    EXPECT_FALSE(std::isnan(breach)) << "the bent shaft reaches the lung voxel at " << lung;
    // The tip reaches the voxel's cell within a voxel of the depth it was placed at.
    EXPECT_NEAR(breach, tip.z() - kEntry.z(), 1.0);
    // Control: the straight needle on the same block never touches it.
    auto straight = model(block, false);
    EXPECT_TRUE(std::isnan(insert(*straight, 55.0)));
}

TEST(BendingForceModel, RefusedBesideTheLockOrThePivotAndWithoutAFoundation)
{
    const Block b(std::nullopt);
    const auto setup = [&](ForceTerms terms, bool foundation) {
        return ForceModelSetup{.layers = {},
            .path = NeedlePath{kEntry, kDir},
            .terms = terms,
            .needle = Needle{},
            .device = {},
            .foundation = foundation ? makeLabelFoundation(*b.field) : nullptr};
    };
    ForceTerms t;
    t.bending.on = true;
    EXPECT_NO_THROW(NeedleForceModel(setup(t, true))); // control
    EXPECT_THROW(NeedleForceModel(setup(t, false)), ValueError);
    t.lock.on = true;
    EXPECT_THROW(NeedleForceModel(setup(t, true)), ValueError);
    t.lock.on = false;
    t.pivot.on = true;
    EXPECT_THROW(NeedleForceModel(setup(t, true)), ValueError);
}

/// The needle held at @p depth with its hub moved sideways by @p sideMm along x
/// (the track held: no axial motion, nothing new cut).
NeedleOutput holdAt(NeedleForceModel& m, double depth, double sideMm, double timeS)
{
    NeedleInput in;
    in.timeS = timeS;
    in.tip = kEntry + (depth - 2.0) * kDir + Vec3d(sideMm, 0.0, 0.0);
    in.direction = kDir;
    NeedleOutput out;
    m.step(in, out);
    return out;
}

/// The lateral part of @p f, across the path.
Vec3d across(const Vec3d& f) { return f - f.dot(kDir) * kDir; }

// §9.5: the beam's hub force reaches the hand through a virtual coupling of the
// device's stiffness k_c in series with the hub's own K. K is checked against the
// beam itself (the change of its hub force when the hub moves with the track held,
// a second solve), and the rendered stiffness against K·k_c/(K + k_c).
TEST(BendingForceModel, TheHubForceReachesTheHandThroughACouplingAtTheDeviceStiffness)
{
    const Block block(std::nullopt);
    for (const double depth : {30.0, 85.0}) { // free spans of 60 and 5 mm
        auto m = model(block, true);
        (void)insert(*m, depth);
        const double t = 1e-3 * (depth / 0.01 + 1.0);
        const NeedleOutput at = holdAt(*m, depth, 0.0, t);
        const Vec3d hub0 = m->bentNeedle()->hubForce();
        const double k = m->bentNeedle()->hubStiffnessNPerMm();
        constexpr double kSideMm = 0.01; // small: the beam stays within its slope limit
        const NeedleOutput moved = holdAt(*m, depth, kSideMm, t + 1e-3);
        ASSERT_FALSE(m->bentNeedle()->slopeLimited());
        // The beam is linear in the hub's offset with the track held: the finite
        // difference is K to round-off (1e-9 relative of forces ~1 N over 0.01 mm).
        constexpr double kLinearRelative = 1e-6;
        const double beamK = -(m->bentNeedle()->hubForce() - hub0).x() / kSideMm;
        EXPECT_NEAR(beamK, k, kLinearRelative * k) << depth;
        EXPECT_NEAR(m->bentNeedle()->hubStiffnessNPerMm(), k, kLinearRelative * k);
        // What the hand feels: the coupled share, in the model's force and nowhere else
        // across the path (no bone, lock or pivot here).
        const double kc = m->device().maxStiffnessNPerMm;
        const double rendered = -(across(moved.modelForce) - across(at.modelForce)).x() / kSideMm;
        EXPECT_NEAR(rendered, k * kc / (k + kc), kLinearRelative * k) << depth;
        EXPECT_LE(rendered, kc * (1.0 + kLinearRelative));
        EXPECT_EQ((across(moved.modelForce) - moved.terms.bending).norm(), 0.0);
        if (depth > 80.0) {
            // Control: with a 5 mm free span the hub is stiffer than the device renders
            // stably (twice k_c here): uncoupled, the hand would get K.
            EXPECT_GT(k, 2.0 * kc);
        }
        // The hub's torque is recorded beside the force, as the beam gives it.
        EXPECT_EQ((moved.hubTorque - m->bentNeedle()->hubTorque()).norm(), 0.0);
        EXPECT_GT(moved.hubTorque.norm(), 0.0);
    }
}

// The device's roll turns the bevel (§9.3): a half turn read from the device
// flips the bevel's force; a reading without a roll (NaN) keeps the last one.
TEST(BendingForceModel, TheDevicesRollTurnsTheBevel)
{
    const Block block(std::nullopt);
    auto m = model(block, true);
    (void)insert(*m, 30.0);
    const Vec3d before = m->bentNeedle()->bevelForce();
    ASSERT_GT(before.norm(), 0.0);
    NeedleInput in;
    in.timeS = 1.0;
    in.tip = kEntry + 28.0 * kDir;
    in.direction = kDir;
    in.rollRad = kPi;
    NeedleOutput out;
    m->step(in, out);
    EXPECT_NEAR((m->bentNeedle()->bevelForce() + before).norm(), 0.0, 1e-9 * before.norm());
    in.timeS = 1.001;
    in.rollRad = std::nan("");
    m->step(in, out);
    EXPECT_NEAR((m->bentNeedle()->bevelForce() + before).norm(), 0.0, 1e-9 * before.norm()) << "kept";
    in.timeS = 1.002;
    in.rollRad = 0.0; // control: turned back
    m->step(in, out);
    EXPECT_NEAR((m->bentNeedle()->bevelForce() - before).norm(), 0.0, 1e-9 * before.norm());
}

// Bone contact pins the beam's tip node (§9.5): once the bent tip meets the bone,
// the hand moving the needle sideways bends the shaft, the tip stays where it met
// the bone (across the path) and nothing more is cut; with the bone's contact force
// rendered or not (the tip stops on bone either way, §1.3). Control: the same
// insertion into muscle without the bone leaves the tip free, and it moves.
TEST(BendingForceModel, BoneContactPinsTheTipNode)
{
    const Block withBone(std::nullopt, /*boneFromZ=*/30), without(std::nullopt);
    for (const int run : {0, 1, 2}) {
        const bool bone = run < 2;
        auto m = model(bone ? withBone : without, true, /*bone term*/ run == 0);
        (void)insert(*m, 33.0); // the tip 1 mm past the bone's surface (z = 29.5 mm)
        ASSERT_EQ(m->bentNeedle()->tipPinned(), bone);
        const Vec3d at = m->bentNeedle()->tip();
        const int cut = m->bentNeedle()->track().count();
        NeedleOutput out;
        for (int i = 1; i <= 50; ++i) { // the hand moves 1 mm sideways in 50 ms, the shaft's axis kept
            NeedleInput in;
            in.timeS = 1.0 + 1e-3 * i;
            in.tip = kEntry + 31.0 * kDir + Vec3d(0.02 * i, 0.0, 0.0);
            in.direction = kDir;
            m->step(in, out);
        }
        const Vec3d moved = across(m->bentNeedle()->tip() - at);
        if (bone) {
            EXPECT_NEAR(moved.norm(), 0.0, 1e-9) << "pinned where it met the bone";
            EXPECT_EQ(m->bentNeedle()->track().count(), cut);
            EXPECT_EQ(m->bentNeedle()->bevelForce().norm(), 0.0);
        } else {
            // Control: the free tip moves (2e-4 mm when written: 30 mm of muscle holds
            // it well), far beyond the pin's round-off.
            EXPECT_GT(moved.norm(), 1e-5) << "the free tip moves with the hand";
        }
    }
}

} // namespace
} // namespace voxhap::haptic
