// SPDX-License-Identifier: Apache-2.0
/// @file TestTrajectory.cpp
/// @brief planning::Planner::analyze on the torso phantom against its analytic
/// geometry and brute-force distances.

#include "PlanningFixtures.h"
#include "core/Errors.h"

#include "haptic/scene/ScriptedInsertion.h"
#include "planning/RiskScore.h"

#include <gtest/gtest.h>

namespace voxhap::planning {
namespace {

using test::torso;

/// Segment boundaries come from voxel cells: a boundary of the analytic surface
/// can move by up to half a voxel diagonal (√3/2 voxel) along the path.
constexpr double kBoundaryMm = 0.87 * test::kTorsoSpacingMm;

/// Clearance from the distance field versus brute force to voxel centres: the field
/// measures to the surface half a voxel beyond the centres (DistanceField.h) and is
/// accurate to half a voxel along an axis, up to a half diagonal obliquely (0.87
/// voxel); the sphere-traced minimum may stop short by its tolerance, the larger of
/// half a voxel and a tenth of the clearance (Clearance.h).
double clearanceTolerance(double c) { return 0.5 + 0.87 * test::kTorsoSpacingMm + std::max(0.5, 0.1 * c); }

TEST(Trajectory, ReferencePathSegmentsFollowThePhantomGeometry)
{
    const auto& f = torso();
    const TrajectoryReport r = f.planner->analyze(f.entry, f.lesion);
    ASSERT_FALSE(r.segments.empty());
    EXPECT_EQ(r.segments.front().tissue, "skin");
    EXPECT_EQ(r.segments.back().tissue, "lesion");
    EXPECT_EQ(r.targetTissue, "lesion");
    EXPECT_NEAR(r.lengthMm, (f.lesion - f.entry).norm(), 1e-9);
    // Every segment's tissue is what the analytic classifier says at its middle,
    // and its ends are where the classifier changes (within a voxel's half diagonal).
    const Vec3d u = (f.lesion - f.entry).normalized();
    for (std::size_t i = 0; i < r.segments.size(); ++i) {
        const auto& s = r.segments[i];
        const double mid = 0.5 * (s.startMm + s.endMm);
        if (s.lengthMm() > 2 * kBoundaryMm) {
            EXPECT_EQ(f.model.classify(f.entry + mid * u), s.label) << s.tissue << " at " << mid << " mm";
        }
        if (i + 1 < r.segments.size()) {
            EXPECT_EQ(f.model.classify(f.entry + (s.endMm - kBoundaryMm) * u), s.label)
                << "before the end of " << s.tissue;
            EXPECT_NE(f.model.classify(f.entry + (s.endMm + kBoundaryMm) * u), s.label)
                << "after the end of " << s.tissue;
        }
    }
    // The vertebral body's shell and marrow hold the lesion: bone, but not an obstacle.
    EXPECT_GE(r.boneEntries, 1);
    EXPECT_EQ(r.boneObstacles, 0);
    EXPECT_FALSE(r.hasWarning("critical_breach"));
    EXPECT_FALSE(r.hasWarning("needle_too_short")); // about 80 mm for a 150 mm needle
}

TEST(Trajectory, ClearancesAgreeWithBruteForceDistances)
{
    const auto& f = torso();
    const TrajectoryReport r = f.planner->analyze(f.entry, f.lesion);
    ASSERT_FALSE(r.clearances.empty());
    for (const auto& c : r.clearances) {
        const double bf = test::bruteForceClearance(*f.volume, c.tissue, f.entry, f.lesion);
        if (c.beyondBand) {
            EXPECT_GT(bf + clearanceTolerance(c.minMm), f.planner->distanceBandMm()) << c.tissue;
        } else {
            EXPECT_NEAR(c.minMm, bf - 0.5 * test::kTorsoSpacingMm, clearanceTolerance(c.minMm)) << c.tissue;
        }
    }
}

TEST(Trajectory, PathThroughTheKidneyIsFlagged)
{
    const auto& f = torso();
    // Aim from the lesion through the left kidney's centre and on to the skin.
    const Vec3d kidney = *volume::phantomLandmark(*f.volume, "kidney_left");
    const Vec3d out = (kidney - f.lesion).normalized();
    const auto runs = f.planner->trace(f.lesion, out, 400.0);
    ASSERT_FALSE(runs.empty());
    const Vec3d entry = f.lesion + runs.back().endMm * out;
    const TrajectoryReport r = f.planner->analyze(entry, f.lesion);
    EXPECT_TRUE(r.hasWarning("critical_breach"));
    EXPECT_EQ(r.nearestStructure, "kidney");
    EXPECT_LT(r.minClearanceMm, 0.0);
    const bool crossesKidney =
        std::any_of(r.segments.begin(), r.segments.end(), [](const auto& s) { return s.tissue == "kidney"; });
    EXPECT_TRUE(crossesKidney);
    EXPECT_GE(r.risk.total, 100.0); // the breach term alone (RiskScore.h)
}

TEST(Trajectory, TooShortNeedleAndForceLimitAreWarned)
{
    const auto& f = torso();
    haptic::Scene short_ = f.scene;
    short_.needle.lengthMm = 40.0;  // shorter than the ~80 mm path
    short_.device.maxForceN = 1e-3; // any resistance exceeds it
    const Planner p(f.volume, test::table(), short_);
    const TrajectoryReport r = p.analyze(f.entry, f.lesion);
    EXPECT_TRUE(r.hasWarning("needle_too_short"));
    EXPECT_TRUE(r.hasWarning("force_above_device_limit"));
    EXPECT_EQ(r.risk.tooShort, 1.0);
    EXPECT_EQ(r.risk.overForce, 1.0);
}

TEST(Trajectory, RiskScoreFollowsItsFormula)
{
    TrajectoryReport r;
    r.lengthMm = 75.0;
    r.peakForceN = 2.0;
    r.minClearanceMm = 5.0;
    r.clearances = {{"kidney", 5.0, 0, false}, {"aorta", 30.0, 0, true}};
    r.boneObstacles = 1;
    const RiskTerms t = riskScore(r, 150.0, 8.0, 20.0);
    // 10·1 (bone) + (1 − 5/20) + 0 + 75/150 + 2/8, by hand.
    EXPECT_DOUBLE_EQ(t.total, 10.0 + 0.75 + 0.5 + 0.25);
}

TEST(Trajectory, BadPointsAreRejected)
{
    const auto& f = torso();
    EXPECT_THROW(f.planner->analyze(f.entry, f.entry), ValueError);
    EXPECT_THROW(f.planner->analyze(Vec3d(NAN, 0, 0), f.lesion), ValueError);
}

/// The predicted profile against the model itself: the scripted servo-rate insertion
/// (haptic::runInsertion) of the same scene along the same path.
TEST(ForcePrediction, MatchesTheSimulatedInsertionBeforeBoneContact)
{
    const auto& f = torso();
    const TrajectoryReport r = f.planner->analyze(f.entry, f.lesion);
    ASSERT_TRUE(std::isfinite(r.contactMm)) << "the lesion sits inside the vertebral body's shell";
    ASSERT_GT(r.force.size(), 10u);
    EXPECT_GT(r.peakForceN, 1.0) << "the voxel damping the comparison exercises (§1.2) should build up over the path";

    const haptic::SceneInstance inst(f.scene, f.volume, test::table(), f.entry, f.lesion);
    auto model = inst.makeModel();
    const auto sim = haptic::runInsertion(*model,
        haptic::InsertionScript::constantSpeed(-f.scene.approachMm, r.contactMm, f.scene.speedMmPerS), f.scene.rateHz);
    // The stick-slip proxy lags its slip point by F/k (k the device's stiffness) and
    // the damping integral changes by at most β_max·v_ref per mm of lag; the skin's
    // first mm is where that lag is largest. 0.15 N is about 2% of the 6 N cap.
    constexpr double kToleranceN = 0.15;
    int compared = 0, peaks = 0;
    for (std::size_t i = 0; i < r.force.size(); ++i) {
        const auto& s = r.force[i];
        // A pop (the kyung scene's skin, §2.1 Eq. 4) gives two samples at one depth:
        // the puncture force just before the drop, then the force after it. The first
        // is the simulation's largest force in the ticks before the drop.
        if (i + 1 < r.force.size() && r.force[i + 1].depthMm == s.depthMm) {
            double before = 0.0;
            for (const auto& row : sim.rows) {
                if (row.depthMm < s.depthMm && row.depthMm > s.depthMm - 1.0) before = std::max(before, row.axialN);
            }
            EXPECT_NEAR(s.forceN, before, kToleranceN) << "the pop's peak at " << s.depthMm << " mm";
            ++peaks;
            continue;
        }
        if (s.depthMm < 2.0 || s.depthMm > r.contactMm - 2.0) continue;
        const auto row = std::min_element(sim.rows.begin(), sim.rows.end(), [&](const auto& a, const auto& b) {
            return std::abs(a.depthMm - s.depthMm) < std::abs(b.depthMm - s.depthMm);
        });
        EXPECT_NEAR(s.forceN, row->axialN, kToleranceN) << "at " << s.depthMm << " mm";
        ++compared;
    }
    EXPECT_GT(compared, 10);
    EXPECT_EQ(peaks, sim.summary.pops); // one peak sample per pop: the skin's
}

} // namespace
} // namespace voxhap::planning
