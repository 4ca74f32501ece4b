// SPDX-License-Identifier: Apache-2.0
/// @file TestSliceStack.cpp
/// @brief Slice ordering along the normal and the uniform-grid checks, on
/// hand-made positions whose answers are known by construction.

#include "core/Errors.h"
#include "volume/dicom/detail/SliceStack.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace {

using voxhap::Vec3d;
using namespace voxhap::volume;

/// Positions are exact sums of small binary fractions here: steps come out
/// exact up to a few ulps of ~100 mm.
constexpr double kStepMm = 1e-12;

std::vector<SlicePlacement> stack(int n, const Vec3d& origin, const Vec3d& step)
{
    std::vector<SlicePlacement> s;
    for (int k = 0; k < n; ++k) s.push_back({origin + k * step, std::size_t(k)});
    return s;
}

TEST(SliceStack, OrdersByPositionAlongTheNormalWhateverTheInputOrder)
{
    const Vec3d normal = Vec3d(0, 0.6, 0.8); // oblique unit normal
    auto slices = stack(9, Vec3d(1, 2, 3), 1.25 * normal);
    std::mt19937 rng(7);
    std::shuffle(slices.begin(), slices.end(), rng);
    const auto g = orderSlices(slices, normal);
    ASSERT_EQ(g.slices.size(), 9u);
    for (std::size_t k = 0; k < 9; ++k) EXPECT_EQ(g.slices[k].source, k);
    EXPECT_NEAR(g.step, 1.25, kStepMm);
    EXPECT_TRUE(g.uniform);
    EXPECT_TRUE(g.problem.empty()) << g.problem;

    // Reversed normal: the order reverses too (ascending along the given normal).
    const auto r = orderSlices(slices, -normal);
    EXPECT_EQ(r.slices.front().source, 8u);
}

TEST(SliceStack, CountsMissingSlices)
{
    auto slices = stack(10, Vec3d::Zero(), Vec3d(0, 0, 3.0));
    slices.erase(slices.begin() + 6);
    slices.erase(slices.begin() + 3);
    slices.erase(slices.begin() + 3); // slices 3, 4 and 7 gone
    const auto g = orderSlices(slices, Vec3d::UnitZ());
    EXPECT_FALSE(g.uniform);
    EXPECT_EQ(g.missingSlices, 3);
    EXPECT_NE(g.problem.find("missing"), std::string::npos) << g.problem;
}

TEST(SliceStack, OneGapAmongThreeSlicesIsAMissingSlice)
{
    // Steps 2 and 4: the reference must be the smaller, or the gap reads as uneven spacing.
    std::vector<SlicePlacement> slices{{Vec3d(0, 0, 0), 0}, {Vec3d(0, 0, 2), 1}, {Vec3d(0, 0, 6), 2}};
    const auto g = orderSlices(slices, Vec3d::UnitZ());
    EXPECT_NEAR(g.step, 2.0, kStepMm);
    EXPECT_EQ(g.missingSlices, 1);
}

TEST(SliceStack, UnevenStepIsNotUniform)
{
    auto slices = stack(5, Vec3d::Zero(), Vec3d(0, 0, 2.0));
    slices[4].position.z() += 0.5;
    const auto g = orderSlices(slices, Vec3d::UnitZ());
    EXPECT_FALSE(g.uniform);
    EXPECT_EQ(g.missingSlices, 0);
    EXPECT_NE(g.problem.find("non-uniform"), std::string::npos) << g.problem;
}

TEST(SliceStack, JitterWithinTheToleranceIsUniform)
{
    auto slices = stack(5, Vec3d::Zero(), Vec3d(0, 0, 2.0));
    slices[2].position.z() += 0.5 * kSlicePositionToleranceMm;
    EXPECT_TRUE(orderSlices(slices, Vec3d::UnitZ()).uniform);
}

TEST(SliceStack, TiltIsDetectedWithItsAngle)
{
    const double tilt = 20.0 * voxhap::kPi / 180.0;
    const auto slices = stack(6, Vec3d::Zero(), Vec3d(0, std::tan(tilt), 1.0)); // 1 mm along z, sheared along y
    const auto g = orderSlices(slices, Vec3d::UnitZ());
    EXPECT_TRUE(g.tilted);
    EXPECT_FALSE(g.uniform);
    EXPECT_NEAR(g.tiltDeg, 20.0, 1e-9); // acos of an exact unit vector: round-off only
    EXPECT_NE(g.problem.find("gantry tilt"), std::string::npos) << g.problem;
}

TEST(SliceStack, DuplicatePositionsThrow)
{
    auto slices = stack(3, Vec3d::Zero(), Vec3d(0, 0, 1.0));
    slices.push_back(slices[1]);
    EXPECT_THROW(orderSlices(slices, Vec3d::UnitZ()), voxhap::ValueError);
}

} // namespace
