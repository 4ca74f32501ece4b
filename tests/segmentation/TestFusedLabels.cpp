// SPDX-License-Identifier: Apache-2.0
/// @file TestFusedLabels.cpp
/// @brief Labels from a CT and an MR on one grid: the CT's labels everywhere,
/// bone from the CT whatever T1 says, and the MR's T1 deciding fat against
/// muscle in the CT's soft tissue where it exists.

#include "phantoms/Phantoms.h"
#include "segmentation/FusedLabels.h"
#include "volume/Grids.h"

#include <gtest/gtest.h>

namespace voxhap::segmentation {
namespace {

using volume::Channel;
using volume::FieldStrength;

TEST(FusedLabels, TheSplitIsTheHarmonicMeanOfFatAndMuscleT1)
{
    const auto& t = volume::TissueTable::builtin();
    // physics.md §5.1: fat 290, muscle 856 ms at 1.5 T; 382 and 898 ms at 3 T.
    EXPECT_NEAR(fatMuscleSplitMs(t, FieldStrength::T1_5), 2.0 / (1.0 / 290.0 + 1.0 / 856.0), 1e-9);
    EXPECT_NEAR(fatMuscleSplitMs(t, FieldStrength::T3), 2.0 / (1.0 / 382.0 + 1.0 / 898.0), 1e-9);
}

TEST(FusedLabels, MrT1DecidesFatAndMuscleInTheCtsSoftTissueAndNeverTouchesBone)
{
    const auto& table = volume::TissueTable::builtin();
    volume::LumbarParams lp;
    lp.grid.spacing = Vec3d(1.0, 1.0, 1.0);
    const volume::Volume phantom = volume::makePhantom(volume::lumbarModel(lp, table), lp.grid, table);
    // The CT alone, labelled by the CT rules: the reference.
    auto ctOnly = [&] {
        volume::Volume v(phantom.transformPtr()->copy(), phantom.indexBox());
        v.setGrid(Channel::Hu, std::const_pointer_cast<openvdb::GridBase>(phantom.grid(Channel::Hu)));
        return v;
    };
    volume::Volume reference = ctOnly();
    segment(reference, table);
    // The fused volume: an MR whose T1 says "fat" (200 ms) for x < 0 and "muscle"
    // (1000 ms) for x ≥ 0 over the whole body, bone included; no T1 for z > 20 mm.
    volume::Volume fused = ctOnly();
    auto t1 = volume::FloatGrid::create(volume::kAirT1);
    {
        auto acc = t1->getAccessor();
        auto hu = volume::huGrid(fused)->getConstAccessor();
        const auto& b = fused.indexBox();
        for (int k = b.min.z(); k <= b.max.z(); ++k)
            for (int j = b.min.y(); j <= b.max.y(); ++j)
                for (int i = b.min.x(); i <= b.max.x(); ++i) {
                    const Vec3d w = fused.indexToWorld(Vec3d(i, j, k));
                    if (w.z() > 20.0 || !hu.isValueOn(openvdb::Coord(i, j, k))) continue;
                    acc.setValueOn(openvdb::Coord(i, j, k), w.x() < 0.0 ? 200.0f : 1000.0f);
                }
    }
    fused.setGrid(Channel::T1, t1);
    const FusedLabelReport r = labelFused(fused, table, FieldStrength::T1_5);
    EXPECT_TRUE(r.note.empty()) << r.note;

    const int fat = table.at("fat").id, muscle = table.at("muscle").id, soft = table.at("soft_tissue").id;
    auto want = volume::labelGrid(reference)->getConstAccessor();
    auto got = volume::labelGrid(fused)->getConstAccessor();
    std::int64_t changed = 0, boneUnderMr = 0;
    const auto& b = fused.indexBox();
    for (int k = b.min.z(); k <= b.max.z(); ++k)
        for (int j = b.min.y(); j <= b.max.y(); ++j)
            for (int i = b.min.x(); i <= b.max.x(); ++i) {
                const openvdb::Coord c(i, j, k);
                const Vec3d w = fused.indexToWorld(Vec3d(i, j, k));
                const int ct = want.getValue(c);
                const bool softTissue = ct == fat || ct == muscle || ct == soft;
                const bool underMr = w.z() <= 20.0 && ct != 0;
                int expected = ct;
                if (softTissue && underMr) expected = w.x() < 0.0 ? fat : muscle;
                ASSERT_EQ(got.getValue(c), expected) << "at " << w.transpose() << ", CT label " << ct;
                changed += expected != ct;
                boneUnderMr += underMr && table.at(ct).rigid;
            }
    // The control: the MR did change labels, and bone lay under it unchanged.
    EXPECT_GT(changed, 1000);
    EXPECT_EQ(r.changed, changed);
    EXPECT_GT(boneUnderMr, 1000);
}

TEST(FusedLabels, AnMrThatIsNotT1LeavesTheCtLabelsAndSaysWhy)
{
    const auto& table = volume::TissueTable::builtin();
    volume::SlabParams sp;
    const volume::Volume phantom = volume::makePhantom(volume::slabModel(sp, table), sp.grid, table);
    volume::Volume v(phantom.transformPtr()->copy(), phantom.indexBox());
    v.setGrid(Channel::Hu, std::const_pointer_cast<openvdb::GridBase>(phantom.grid(Channel::Hu)));
    auto intensity = volume::FloatGrid::create(volume::kAirIntensity);
    intensity->tree().topologyUnion(volume::huGrid(phantom)->tree());
    v.setGrid(Channel::Intensity, intensity);
    v.metadata().mrWeighting = volume::MrWeightingKind::T2Weighted;
    const FusedLabelReport r = labelFused(v, table, FieldStrength::T3);
    EXPECT_EQ(r.note, "the MR is T2-weighted, not T1: the labels come from the CT alone");
    EXPECT_EQ(r.changed, 0);
    EXPECT_TRUE(v.has(Channel::Label));
}

} // namespace
} // namespace voxhap::segmentation
