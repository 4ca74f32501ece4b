// SPDX-License-Identifier: Apache-2.0
/// @file TestRealCtPlanning.cpp
/// @brief Planning on the real abdominal CT (../shared/data): segmentation once per
/// binary, then a search from the posterior skin to a vertebral body.

#include "PlanningFixtures.h"
#include "common/BuiltinTable.h"
#include "common/SharedData.h"
#include "haptic/scene/Scene.h"
#include "planning/Search.h"
#include "segmentation/Segmentation.h"
#include "volume/VolumeFile.h"

#include <gtest/gtest.h>

#include <set>

namespace voxhap::planning {
namespace {

struct RealCt {
    std::shared_ptr<volume::Volume> v;
    std::unique_ptr<Planner> planner;
};

const RealCt& realCt()
{
    static const RealCt s = [] {
        RealCt out;
        out.v = std::make_shared<volume::Volume>(volume::loadVolume(test::realCtDir()));
        segmentation::segment(*out.v, test::table());
        out.planner = std::make_unique<Planner>(out.v, test::table(), haptic::loadScene("kyung"));
        return out;
    }();
    return s;
}

class RealCtPlanning : public testing::Test {
protected:
    void SetUp() override { VOXHAP_REQUIRE_DIR(test::realCtDir()); }
};

TEST_F(RealCtPlanning, PosteriorPathToAVertebralBodyCrossesOnlySkinFatMuscleAndBone)
{
    const auto& s = realCt();
    // A lumbar vertebral body found by segmentation: walk the midline of the slice
    // z = 296 mm (mid-abdomen) backward from y = 60 mm, in front of the spine
    // (posterior is +y in LPS): the first cancellous bone met is the front of the
    // vertebral body, not a posterior element.
    const int cancellous = test::table().at("cancellous_bone").id;
    std::optional<Vec3d> body;
    for (double y = 60.0; y < 200.0; y += 1.0) {
        const Vec3d p(4.0, y, 296.0);
        if (s.planner->labelAt(p) == cancellous) {
            body = p;
            break;
        }
    }
    ASSERT_TRUE(body) << "no cancellous bone on the midline";
    // 8 mm into the body from its anterior surface: inside the marrow.
    const Vec3d target = *body + Vec3d(0, 8.0, 0);
    ASSERT_EQ(s.planner->labelAt(target), cancellous);

    SearchConstraints k;
    k.reference = Vec3d(0, 1, 0);
    k.maxAngleDeg = 45.0;
    k.allowBoneObstacles = true; // the posterior elements may stand in the way: reported, not forbidden
    SearchOptions o;
    o.stepDeg = 3.0;
    const SearchResult res = search(*s.planner, target, k, o);
    ASSERT_FALSE(res.ranked.empty()) << "no feasible path";
    const TrajectoryReport& best = res.ranked.front();
    const std::set<std::string> allowed{"skin", "fat", "muscle", "cortical_bone", "cancellous_bone"};
    for (const auto& seg : best.segments) EXPECT_TRUE(allowed.count(seg.tissue)) << seg.tissue << " on the path";
    EXPECT_EQ(best.segments.front().tissue, "skin");
    EXPECT_GT(best.entry.y(), target.y()) << "the entry is posterior of the target";
    ASSERT_FALSE(best.clearances.empty());
    // Independent of the distance fields the search relied on: voxel-centre
    // distances of each segmented critical structure to the path.
    for (const auto& c : best.clearances) {
        EXPECT_GE(
            test::bruteForceClearance(*s.v, c.tissue, best.entry, best.target), s.planner->options().minClearanceMm)
            << c.tissue;
    }
}

} // namespace
} // namespace voxhap::planning
