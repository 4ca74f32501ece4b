// SPDX-License-Identifier: Apache-2.0
/// @file TestMrSegmentation.cpp
/// @brief MR T1: fat and muscle by Otsu inside the body (issue 7 item 2), on the
/// sphere phantom's t1 grid (a muscle sphere in fat, physics.md §7 R5) with noise.

#include "SegmentationFixtures.h"

#include "common/BuiltinTable.h"
#include "phantoms/Phantoms.h"
#include "segmentation/MrSegmentation.h"
#include "segmentation/Segmentation.h"
#include "volume/Grids.h"

#include <gtest/gtest.h>

#include <cmath>

namespace voxhap::segmentation {
namespace {

using test::table;

// T1 noise [ms]: 10 % of fat's 290 ms, a T1 map's typical precision.
constexpr double kNoiseMs = 29.0;

TEST(MrSegmentation, OtsuSplitsTwoClustersBetweenThem)
{
    std::vector<float> v;
    for (int i = 0; i < 1000; ++i) v.push_back(290.0f + float(i % 21) - 10.0f);
    for (int i = 0; i < 3000; ++i) v.push_back(856.0f + float(i % 41) - 20.0f);
    const double t = otsuThreshold(v);
    EXPECT_GT(t, 300.0);
    EXPECT_LT(t, 836.0);
}

TEST(MrSegmentation, SpherePhantomFatAndMuscleDiceAtLeast095)
{
    volume::SphereParams p;
    p.grid.spacing = Vec3d(0.5, 0.5, 0.5);
    volume::Volume v = volume::makePhantom(volume::sphereModel(p, table()), p.grid, table());
    const auto truth = openvdb::gridPtrCast<volume::LabelGrid>(v.grid(volume::Channel::Label)->deepCopyGrid());
    auto t1 = openvdb::gridPtrCast<volume::FloatGrid>(v.grid(volume::Channel::T1)->deepCopyGrid());
    test::addNoise(*t1, kNoiseMs, 5);
    v.setGrid(volume::Channel::T1, t1);
    v.removeGrid(volume::Channel::Hu);
    v.removeGrid(volume::Channel::Label);
    const SegmentReport r = segment(v, table());
    EXPECT_EQ(r.method, "mr");
    // The phantom is a block without skin; the segmentation puts a 2 mm skin shell on
    // every body surface. Compare the voxels deeper than that shell, 3 mm in from each face.
    volume::IndexBox inner = v.indexBox();
    const int shell = int(std::ceil(3.0 / 0.5));
    inner.min += Vec3i::Constant(shell);
    inner.max -= Vec3i::Constant(shell);
    const auto result = volume::labelGrid(v);
    const int fat = table().at("fat").id, muscle = table().at("muscle").id;
    EXPECT_GE(test::dice(*truth, *result, inner, {fat}, {fat}), test::kMinDice);
    EXPECT_GE(test::dice(*truth, *result, inner, {muscle}, {muscle}), test::kMinDice);
}

} // namespace
} // namespace voxhap::segmentation
