// SPDX-License-Identifier: Apache-2.0
/// @file TestBendingForceModel.cpp
/// @brief The bending needle inside the force model (physics.md §9.5): the model
/// integrates along the bent shaft and reads the bent tip, so a critical voxel
/// that only the bent needle reaches raises the warning; with bending off, the
/// same insertion never touches it (the control). And the terms the beam
/// replaces are refused beside it.

#include "common/BuiltinTable.h"
#include "common/Phantom.h"

#include "haptic/beam/Foundation.h"
#include "haptic/force/NeedleForceModel.h"
#include "haptic/models/LayerTables.h"
#include "haptic/shaft/LabelTrace.h"
#include "core/Errors.h"
#include "volume/Grids.h"

#include <gtest/gtest.h>

#include <cmath>

namespace voxhap::haptic {
namespace {

using voxhap::test::table;

/// A block of muscle, 1 mm voxels, the needle entering its face z = −0.5 along +z;
/// with @p lung, one lung voxel there.
struct Block {
    volume::LabelGrid::Ptr labels = volume::LabelGrid::create(0);
    std::unique_ptr<MaterialField> field;
    explicit Block(const std::optional<openvdb::Coord>& lung)
    {
        labels->setTransform(openvdb::math::Transform::createLinearTransform(1.0));
        labels->tree().fill(
            openvdb::CoordBBox(openvdb::Coord(-40, -40, 0), openvdb::Coord(40, 40, 100)), table().at("muscle").id);
        if (lung) labels->tree().setValue(*lung, table().at("lung").id);
        field = std::make_unique<MaterialField>(test::betaFromLabels(*labels, test::testBeta()), labels, table());
    }
};

const Vec3d kEntry(0.0, 0.0, -0.5), kDir(0.0, 0.0, 1.0);

std::unique_ptr<NeedleForceModel> model(const Block& b, bool bending)
{
    LayerRecipe recipe;
    recipe.model = LayerModel::Kyung;
    ForceTerms terms;
    terms.tip = terms.cutting = terms.viscous = false;
    terms.damping.on = true;
    terms.critical = true;
    terms.bending.on = bending;
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

} // namespace
} // namespace voxhap::haptic
