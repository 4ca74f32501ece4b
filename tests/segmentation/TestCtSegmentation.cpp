// SPDX-License-Identifier: Apache-2.0
/// @file TestCtSegmentation.cpp
/// @brief CT segmentation of the torso phantom (physics.md §1.1), generated
/// from the tissue table with scanner noise: every class recovered with
/// Dice ≥ 0.95 (issue 7), distance fields written.

#include "SegmentationFixtures.h"

#include "segmentation/DistanceField.h"
#include "segmentation/Segmentation.h"
#include "volume/Grids.h"
#include "volume/phantoms/Phantoms.h"

#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <set>

namespace voxhap::segmentation {
namespace {

using test::enhancedTable;

// CT quantum noise in soft tissue [HU]: the upper end of a routine abdominal scan.
constexpr double kNoiseHu = 20.0;

struct TorsoCase {
    std::unique_ptr<volume::Volume> v;
    volume::LabelGrid::Ptr truth;
    SegmentReport report;
};

const TorsoCase& torso()
{
    static const TorsoCase c = [] {
        TorsoCase t;
        const auto& table = enhancedTable();
        volume::TorsoParams p;
        // 0.5 mm in-plane keeps the 2 mm skin 4 voxels thick; 3 mm slices like the test CT.
        p.grid.spacing = Vec3d(0.5, 0.5, 3.0);
        t.v = std::make_unique<volume::Volume>(volume::makePhantom(volume::torsoModel(p, table), p.grid, table));
        t.truth = openvdb::gridPtrCast<volume::LabelGrid>(t.v->grid(volume::Channel::Label)->deepCopyGrid());
        auto hu = openvdb::gridPtrCast<volume::FloatGrid>(t.v->grid(volume::Channel::Hu)->deepCopyGrid());
        test::addNoise(*hu, kNoiseHu, 11);
        t.v->setGrid(volume::Channel::Hu, hu);
        t.v->removeGrid(volume::Channel::Label);
        t.v->removeGrid(volume::Channel::T1);
        t.report = segment(*t.v, table);
        return t;
    }();
    return c;
}

TEST(CtSegmentation, TorsoPhantomEveryClassDiceAtLeast095)
{
    const TorsoCase& c = torso();
    EXPECT_EQ(c.report.method, "ct");
    const auto& table = enhancedTable();
    const auto id = [&](const char* n) { return table.at(n).id; };
    const auto result = volume::labelGrid(*c.v);
    ASSERT_TRUE(result);
    // The phantom's soft tissues that CT numbers cannot tell from muscle (ligaments,
    // dura, CSF, cord, disc, the lytic lesion) form one class with it; the result's
    // soft_tissue and spinal_cord belong to it too (the canal is tested below).
    const std::set<int> lean{id("muscle"), id("supraspinous_ligament"), id("interspinous_ligament"),
        id("ligamentum_flavum"), id("dura"), id("csf"), id("spinal_cord"), id("intervertebral_disc"), id("lesion"),
        id("soft_tissue"), id("epidural_space")};
    const std::map<std::string, std::set<int>> classes{
        {"air", {0}},
        {"skin", {id("skin")}},
        {"fat", {id("fat")}},
        {"muscle and lean soft tissue", lean},
        {"lung", {id("lung")}},
        {"kidney", {id("kidney")}},
        {"aorta", {id("aorta")}},
        {"cortical_bone", {id("cortical_bone")}},
        {"cancellous_bone", {id("cancellous_bone")}},
    };
    for (const auto& [name, ids] : classes) {
        const double d = test::dice(*c.truth, *result, c.v->indexBox(), ids, ids);
        EXPECT_GE(d, test::kMinDice) << name;
        std::cout << "dice " << name << " " << d << "\n";
    }
}

TEST(CtSegmentation, DistanceFieldsOfTheCriticalStructuresPresent)
{
    const TorsoCase& c = torso();
    // No spinal canal here: it is found as the hole of a closed bony ring (pedicles,
    // laminae), and the phantom's arch does not join its vertebral body. The real-CT
    // test checks the canal.
    for (const char* name : {"lung", "kidney", "aorta"}) {
        const auto g = openvdb::gridConstPtrCast<volume::FloatGrid>(c.v->derived(distanceFieldName(name)));
        ASSERT_TRUE(g) << name;
    }
    // The aorta's axis is 11 mm inside its wall; the lesion centre lies 33 mm from
    // the aorta's axis, 22 mm from its wall (TorsoPhantom.cpp): both well inside the
    // 30 mm band. Tolerance: 2 mm, the voxels' half diagonal (1.6 mm) rounded up.
    const auto sdf = openvdb::gridConstPtrCast<volume::FloatGrid>(c.v->derived(distanceFieldName("aorta")));
    const auto sample = [&](const Vec3d& w) {
        const Vec3d ijk = c.v->worldToIndex(w);
        return sdf->getConstAccessor().getValue(
            openvdb::Coord(int(std::lround(ijk.x())), int(std::lround(ijk.y())), int(std::lround(ijk.z()))));
    };
    const Vec3d aorta = *volume::phantomLandmark(*c.v, "aorta");
    const Vec3d lesion = *volume::phantomLandmark(*c.v, "lesion");
    EXPECT_NEAR(sample(aorta), -11.0, 2.0);
    EXPECT_NEAR(sample(lesion), (lesion - aorta).head<2>().norm() - 11.0, 2.0);
}

TEST(CtSegmentation, SummaryVolumesMatchTheVoxelCounts)
{
    const TorsoCase& c = torso();
    const double voxelMl = 0.5 * 0.5 * 3.0 * 1e-3;
    ASSERT_FALSE(c.report.labels.empty());
    for (const auto& l : c.report.labels) {
        EXPECT_NEAR(l.ml, double(l.voxels) * voxelMl, 1e-9 * l.ml) << l.name;
        EXPECT_LE(l.bounds[0].x(), l.bounds[1].x());
    }
}

} // namespace
} // namespace voxhap::segmentation
