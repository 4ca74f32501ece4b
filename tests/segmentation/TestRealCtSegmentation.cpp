// SPDX-License-Identifier: Apache-2.0
/// @file TestRealCtSegmentation.cpp
/// @brief Segmentation of the real abdominal CT (../shared/data, 512 × 512 × 134,
/// 1.07 × 1.07 × 3 mm, contrast-enhanced, lower chest to mid abdomen, supine on a
/// table). No reference segmentation exists for it, so the checks are anatomical
/// facts with ranges that say where they come from.

#include "SegmentationFixtures.h"
#include "common/BuiltinTable.h"
#include "common/SharedData.h"
#include "segmentation/DistanceField.h"
#include "segmentation/Segmentation.h"
#include "segmentation/TorsoExtent.h"
#include "volume/Grids.h"
#include "volume/VolumeFile.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>

namespace voxhap::segmentation {
namespace {

using test::table;

struct Segmented {
    std::unique_ptr<volume::Volume> v;
    SegmentReport report;
    std::map<std::string, LabelSummary> byName;
};

const Segmented& realCt()
{
    static const Segmented s = [] {
        Segmented out;
        out.v = std::make_unique<volume::Volume>(volume::loadVolume(test::realCtDir()));
        out.report = segment(*out.v, table());
        for (const auto& l : out.report.labels) out.byName[l.name] = l;
        return out;
    }();
    return s;
}

float sdfAt(const volume::Volume& v, const std::string& tissue, const Vec3d& w)
{
    const auto g = openvdb::gridConstPtrCast<volume::FloatGrid>(v.derived(distanceFieldName(tissue)));
    const Vec3d ijk = v.worldToIndex(w);
    return g->getConstAccessor().getValue(
        openvdb::Coord(int(std::lround(ijk.x())), int(std::lround(ijk.y())), int(std::lround(ijk.z()))));
}

class RealCtSegmentation : public testing::Test {
protected:
    void SetUp() override { VOXHAP_REQUIRE_DIR(test::realCtDir()); }
};

TEST_F(RealCtSegmentation, BodyHoldsThePatientAndExcludesTheTable)
{
    const auto& s = realCt();
    // On the midline at z = 250 mm the posterior skin is at y ≈ 222 mm and the
    // table top, under an air gap, at y ≈ 290 mm (found by inspecting the data).
    EXPECT_NE(test::labelAtWorld(*s.v, Vec3d(0, 215, 250)), 0);
    EXPECT_EQ(test::labelAtWorld(*s.v, Vec3d(0, 290, 250)), 0);
    double maxY = -1e9, totalMl = 0;
    for (const auto& l : s.report.labels) {
        maxY = std::max(maxY, l.bounds[1].y());
        totalMl += l.ml;
    }
    EXPECT_LT(maxY, 270.0) << "a label reaches the table";
    // A 402 mm segment of an adult trunk, lower chest to pelvis: 20–50 L (an
    // ellipse of 30 × 22 cm over 40 cm is 21 L; the arms, when in view, add more).
    EXPECT_GT(totalMl, 20000.0);
    EXPECT_LT(totalMl, 50000.0);
}

TEST_F(RealCtSegmentation, TheTorsoRulesApplyToEverySlice)
{
    // Issue 27 item 11: the anatomy test (TorsoExtent.h) must not misfire on a trunk.
    // Every slice of this abdomen is wider than the 240 mm threshold; the widest
    // (arms beside the trunk) is at most the 550 mm field of view (512 × 1.07 mm).
    const auto& s = realCt();
    EXPECT_GT(s.report.bodyWidthMm, kMinTorsoWidthMm);
    EXPECT_LT(s.report.bodyWidthMm, 550.0);
    EXPECT_EQ(s.report.torsoFraction, 1.0);
    EXPECT_TRUE(s.report.notes.empty()) << ::testing::PrintToString(s.report.notes);
}

TEST_F(RealCtSegmentation, LungLiesInTheLungBasesOnly)
{
    const auto& s = realCt();
    ASSERT_TRUE(s.byName.count("lung"));
    const LabelSummary& lung = s.byName.at("lung");
    // The scan ends superiorly at z = 486 mm; the diaphragm domes lie some 15 cm
    // below the top of the scan here: no lung below z = 300 mm.
    EXPECT_GT(lung.bounds[0].z(), 300.0);
    // Both lung bases: more than 1 L, less than whole lungs (4–6 L).
    EXPECT_GT(lung.ml, 1000.0);
    EXPECT_LT(lung.ml, 4000.0);
}

TEST_F(RealCtSegmentation, VertebralBodyPointIsBone)
{
    const auto& s = realCt();
    const int l = test::labelAtWorld(*s.v, Vec3d(4.3, 120.5, 295.91)); // as in TestRealCt.cpp
    EXPECT_TRUE(l == table().at("cancellous_bone").id || l == table().at("cortical_bone").id) << l;
}

TEST_F(RealCtSegmentation, LabelVolumesArePlausible)
{
    const auto& s = realCt();
    const auto ml = [&](const char* n) { return s.byName.count(n) ? s.byName.at(n).ml : 0.0; };
    // Two adult kidneys: 120–200 ml each (imaging norms), plus the partial volume at
    // their edges: 150–700 ml.
    EXPECT_GT(ml("kidney"), 150.0);
    EXPECT_LT(ml("kidney"), 700.0);
    // Abdominal aorta: 2–2.5 cm across over the 20–27 cm in view: 60–130 ml; 30–200
    // leaves room for where the lumen ends in the field of view.
    EXPECT_GT(ml("aorta"), 30.0);
    EXPECT_LT(ml("aorta"), 200.0);
    // Spine, ribs and the top of the pelvis in 40 cm: 0.8–3 L.
    EXPECT_GT(ml("cortical_bone") + ml("cancellous_bone"), 800.0);
    EXPECT_LT(ml("cortical_bone") + ml("cancellous_bone"), 3000.0);
    // Fat and muscle each several litres: 3–25 L.
    for (const char* n : {"fat", "muscle"}) {
        EXPECT_GT(ml(n), 3000.0) << n;
        EXPECT_LT(ml(n), 25000.0) << n;
    }
}

TEST_F(RealCtSegmentation, SpinalCanalBehindTheVertebralBodies)
{
    const auto& s = realCt();
    ASSERT_TRUE(s.byName.count("spinal_cord"));
    const LabelSummary& canal = s.byName.at("spinal_cord");
    // Behind the vertebral bodies (centre y ≈ 120 mm at x ≈ 4 mm), about 15 mm across.
    EXPECT_GT(canal.bounds[0].x(), -25.0);
    EXPECT_LT(canal.bounds[1].x(), 30.0);
    EXPECT_GT(canal.bounds[0].y(), 110.0);
    EXPECT_LT(canal.bounds[1].y(), 175.0);
    // 1–4 cm² over at least 3 cm of spine.
    EXPECT_GT(canal.ml, 3.0);
    EXPECT_LT(canal.ml, 160.0);
}

TEST_F(RealCtSegmentation, DistanceFieldsGiveClearanceInMillimetres)
{
    const auto& s = realCt();
    const Vec3d vertebra(4.3, 120.5, 295.91);
    // A voxel's centre lies within its half diagonal of any point of it: 0.5·√(1.07² +
    // 1.07² + 3²) = 1.68 mm, rounded up to 2 mm.
    constexpr double kVoxelHalfDiagonalMm = 2.0;
    // The kidneys lie lateral of the vertebral body: farther from its centre than half
    // a lumbar body's transverse width (40–50 mm), so more than 20 mm, less a voxel.
    // (This patient reads about 26 mm: not the 30 mm or more an earlier comment
    // promised, which would have saturated the 30 mm band.)
    EXPECT_GE(sdfAt(*s.v, "kidney", vertebra), 20.0 - kVoxelHalfDiagonalMm);
    // Inside the aorta the field is negative: at the centre of the box of aorta voxels
    // in the slice at z = 300 mm (a round lumen holds its box's centre), no deeper than
    // half the box's larger side (the lumen's radius at most).
    ASSERT_TRUE(s.byName.count("aorta"));
    const int aortaId = table().at("aorta").id;
    const auto labels = volume::labelGrid(*s.v);
    Vec3d lo = Vec3d::Constant(1e9), hi = Vec3d::Constant(-1e9);
    for (auto it = labels->cbeginValueOn(); it; ++it) {
        if (*it != aortaId) continue;
        const openvdb::CoordBBox box = it.getBoundingBox(); // one voxel, or a tile of them
        for (auto c = box.begin(); c; ++c) {
            const Vec3d w = s.v->indexToWorld(Vec3d((*c).x(), (*c).y(), (*c).z()));
            if (std::abs(w.z() - 300.0) > 1.5) continue; // the 3 mm slice holding z = 300
            lo = lo.cwiseMin(w), hi = hi.cwiseMax(w);
        }
    }
    ASSERT_LE(lo.x(), hi.x()) << "no aorta voxel in the slice at z = 300 mm";
    const Vec3d centre = 0.5 * (lo + hi);
    const double halfSide = 0.5 * std::max(hi.x() - lo.x(), hi.y() - lo.y());
    EXPECT_LT(sdfAt(*s.v, "aorta", centre), 0.0) << "centre " << centre.transpose();
    EXPECT_GE(sdfAt(*s.v, "aorta", centre), -(halfSide + kVoxelHalfDiagonalMm)) << "centre " << centre.transpose();
    EXPECT_EQ(s.report.distanceFields.size(), 4u); // lung, kidney, aorta, spinal_cord
}

} // namespace
} // namespace voxhap::segmentation
