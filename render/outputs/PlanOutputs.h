// SPDX-License-Identifier: Apache-2.0
/// @file PlanOutputs.h
/// @brief What `voxhap plan` and `voxhap demo` leave behind for a plan:
/// report.json, paths.mrk.json, views.png (slices through the first target and
/// a 3D view, every path drawn) and force-depth.png (the first path's predicted
/// profile), replacing an earlier plan's outputs together.
#pragma once

#include "planning/Planner.h"
#include "planning/Trajectory.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace voxhap::render {

class DisplayGuard;

/// @brief The files written; views and plot empty when not written.
struct PlanFiles {
    std::string report, markups, views, plot;
    std::string why;   ///< why there is no plot
    std::string why3d; ///< why views.png has no 3D view (no X display)
};

/// @brief report.json, paths.mrk.json, views.png (when @p views and there is a
/// path) and force-depth.png (gnuplot drawing while the views render) in @p outDir.
/// An output this plan does not make removes an earlier plan's.
/// @param display a display started earlier without waiting (DisplayGuard's
///        wait = false), so that Xvfb came up while the caller loaded and planned;
///        null: one is started here when the views need it.
/// @throw IoError naming the file
PlanFiles writePlanOutputs(const planning::Planner& planner, const std::vector<planning::TrajectoryReport>& paths,
    const nlohmann::json& report, const std::string& outDir, bool views, DisplayGuard* display = nullptr);

} // namespace voxhap::render
