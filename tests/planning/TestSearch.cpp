// SPDX-License-Identifier: Apache-2.0
/// @file TestSearch.cpp
/// @brief planning::search on the torso phantom; the direction grid and the Pareto set.

#include "PlanningFixtures.h"
#include "core/Errors.h"

#include "planning/Search.h"

#include <gtest/gtest.h>

#include <random>

namespace voxhap::planning {
namespace {

using test::torso;

double deg(double rad) { return rad * 180.0 / kPi; }

TEST(DirectionGrid, CoversTheCapEvenly)
{
    const Vec3d axis = Vec3d(1, 2, 0.5).normalized();
    const double maxDeg = 40.0, step = 5.0;
    const auto dirs = directionGrid(axis, maxDeg, step);
    double minPair = 1e9;
    for (std::size_t i = 0; i < dirs.size(); ++i) {
        EXPECT_NEAR(dirs[i].norm(), 1.0, 1e-12);
        EXPECT_LE(deg(std::acos(std::clamp(dirs[i].dot(axis), -1.0, 1.0))), maxDeg + 1e-9);
        for (std::size_t j = 0; j < i; ++j)
            minPair = std::min(minPair, deg(std::acos(std::clamp(dirs[i].dot(dirs[j]), -1.0, 1.0))));
    }
    // Rings are `step` apart and each ring's azimuths about `step` apart: no two
    // directions closer than half a step, and the count is near the cap's area over step².
    EXPECT_GT(minPair, 0.5 * step);
    const double capArea = 2 * kPi * (1 - std::cos(degToRad(maxDeg)));
    EXPECT_NEAR(
        double(dirs.size()), capArea / std::pow(degToRad(step), 2), 0.25 * capArea / std::pow(degToRad(step), 2));
}

TEST(Pareto, KeepsExactlyTheNonDominated)
{
    const auto make = [](double c, double l, double fN) {
        TrajectoryReport r;
        r.minClearanceMm = c, r.lengthMm = l, r.peakForceN = fN;
        return r;
    };
    // b dominates d (better clearance, same length, less force); a, b, c trade off.
    const std::vector<TrajectoryReport> v{
        make(10, 80, 3), make(20, 90, 2), make(5, 70, 4), make(15, 90, 2.5), make(40, 100, 5)};
    const auto front = paretoFront(v, 30.0);
    // With the band at 30 mm, e's clearance counts as 30: still the best, so kept.
    EXPECT_EQ(front, (std::vector<std::size_t>{0, 1, 2, 4}));
}

TEST(Pareto, AgreesWithTheDefinitionOnRandomCandidates)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> c(0, 40), l(60, 150), f(0, 8);
    std::vector<TrajectoryReport> v(300);
    for (auto& r : v)
        r.minClearanceMm = std::round(c(rng)), r.lengthMm = std::round(l(rng)), r.peakForceN = std::round(f(rng));
    const double band = 30.0;
    // The definition, pair by pair: kept unless another is no worse in all three and better in one.
    std::vector<std::size_t> expected;
    for (std::size_t i = 0; i < v.size(); ++i) {
        bool dominated = false;
        for (std::size_t j = 0; j < v.size() && !dominated; ++j) {
            const double ci = std::min(v[i].minClearanceMm, band), cj = std::min(v[j].minClearanceMm, band);
            dominated = cj >= ci && v[j].lengthMm <= v[i].lengthMm && v[j].peakForceN <= v[i].peakForceN &&
                (cj > ci || v[j].lengthMm < v[i].lengthMm || v[j].peakForceN < v[i].peakForceN);
        }
        if (!dominated) expected.push_back(i);
    }
    EXPECT_EQ(paretoFront(v, band), expected);
}

TEST(Search, CoarseGridFindsASafePathToTheLesion)
{
    const auto& f = torso();
    SearchConstraints k;
    k.reference = Vec3d(0, 1, 0); // posterior: the patient lies prone
    k.maxAngleDeg = 60.0;
    SearchOptions o;
    o.stepDeg = 6.0; // coarse
    o.top = 5;
    const SearchResult res = search(*f.planner, f.lesion, k, o);
    ASSERT_FALSE(res.ranked.empty()) << "no feasible path";
    EXPECT_GT(res.counts.analysed, 50);
    EXPECT_GT(res.counts.breach, 0) << "some directions cross the kidney, lung or cord";
    const TrajectoryReport& best = res.ranked.front();
    EXPECT_EQ(best.targetTissue, "lesion");
    EXPECT_EQ(best.segments.front().tissue, "skin");
    EXPECT_FALSE(best.hasWarning("critical_breach"));
    EXPECT_FALSE(best.hasWarning("needle_too_short"));
    // Independent check of the clearances the search relied on.
    for (const char* organ : {"kidney", "lung", "aorta", "spinal_cord"}) {
        const double bf = test::bruteForceClearance(*f.volume, organ, best.entry, best.target);
        EXPECT_GE(bf, f.planner->options().minClearanceMm) << organ;
    }
    EXPECT_FALSE(res.pareto.empty());
}

TEST(Search, EntryBoxAndAngleConstrainTheEntries)
{
    const auto& f = torso();
    SearchConstraints k;
    k.reference = Vec3d(0, 1, 0);
    k.maxAngleDeg = 40.0;
    k.entryBox = Box{Vec3d(0, -50, -20), Vec3d(80, 10, 20)}; // the left back only
    SearchOptions o;
    o.stepDeg = 5.0;
    const SearchResult res = search(*f.planner, f.lesion, k, o);
    ASSERT_FALSE(res.ranked.empty());
    EXPECT_GT(res.counts.outsideBox, 0);
    for (const auto& r : res.ranked) {
        EXPECT_TRUE(k.entryBox->contains(r.entry));
        const Vec3d out = (r.entry - r.target).normalized();
        EXPECT_LE(deg(std::acos(out.dot(k.reference))), k.maxAngleDeg + 1e-6);
    }
}

TEST(Search, BadConstraintsAreRejected)
{
    const auto& f = torso();
    SearchConstraints k;
    k.reference = Vec3d::Zero();
    EXPECT_THROW(search(*f.planner, f.lesion, k), ValueError);
    EXPECT_THROW(search(*f.planner, Vec3d(0, 500, 0), SearchConstraints{}), ValueError); // target in the air
}

} // namespace
} // namespace voxhap::planning
