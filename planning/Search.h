// SPDX-License-Identifier: Apache-2.0
/// @file Search.h
/// @brief Candidate entries for a target: directions on a grid
/// around a reference direction, each traced outward from the target to the
/// skin, analysed in parallel (TBB), filtered by the constraints and ranked by
/// risk; plus the Pareto set over clearance, length and peak predicted force.
#pragma once

#include "planning/Planner.h"

#include <cstdint>
#include <optional>
#include <vector>

namespace voxhap::planning {

/// @brief An axis-aligned box [mm, LPS].
struct Box {
    Vec3d min{0, 0, 0}, max{0, 0, 0};
    bool contains(const Vec3d& p) const { return (p.array() >= min.array()).all() && (p.array() <= max.array()).all(); }
};

struct SearchConstraints {
    /// Outward direction from the target toward the entry (e.g. posterior, +y in LPS).
    Vec3d reference{0, 1, 0};
    double maxAngleDeg = 45.0;       ///< largest angle between a path (target → entry) and the reference
    double maxLengthMm = 0;          ///< longest path; 0: the scene's needle length
    bool skinEntry = true;           ///< the entry must lie on the skin label (when the table has one)
    std::optional<Box> entryBox;     ///< the entry must lie in this box
    bool allowBoneObstacles = false; ///< accept paths that cross bone other than the target's own
};

struct SearchOptions {
    double stepDeg = 2.0; ///< angular spacing of the direction grid [deg]
    int top = 10;         ///< ranked candidates kept
};

/// @brief Why a direction gave no candidate, or a candidate was rejected.
struct SearchCounts {
    std::int64_t directions = 0; ///< directions on the grid
    std::int64_t analysed = 0;   ///< candidates fully analysed (entry found)
    std::int64_t feasible = 0;   ///< analysed and within every constraint
    std::int64_t noSkinExit = 0; ///< the body does not end within the maximum length
    std::int64_t notSkin = 0;    ///< the exit is not on the skin
    std::int64_t outsideBox = 0; ///< the entry is outside the entry box
    std::int64_t breach = 0, clearance = 0, bone = 0, tooLong = 0;
};

struct SearchResult {
    std::vector<TrajectoryReport> ranked; ///< feasible, lowest risk first, at most options.top
    std::vector<TrajectoryReport> pareto; ///< non-dominated feasible candidates, by clearance (descending)
    SearchCounts counts;
    double seconds = 0;
    double maxLengthMm = 0; ///< the longest path allowed (the constraint, or the needle's length)
};

/// @brief The unit directions of the grid: rings at polar angles 0, s, 2s, … ≤ the
/// maximum about @p axis, each ring with round(2π·sin θ / s) evenly spaced azimuths,
/// so neighbours are about s apart everywhere on the cap.
std::vector<Vec3d> directionGrid(const Vec3d& axis, double maxAngleDeg, double stepDeg);

/// @brief Search entries for @p target. @throw ValueError on a bad constraint or option
SearchResult search(const Planner& planner, const Vec3d& target, const SearchConstraints& constraints,
    const SearchOptions& options = {});

/// @brief Indices of the candidates no other candidate dominates: at least as good in
/// clearance (higher; capped at the distance band, beyond which it is unknown),
/// length and peak force (lower), and better in one.
std::vector<std::size_t> paretoFront(const std::vector<TrajectoryReport>& candidates, double bandMm);

} // namespace voxhap::planning
