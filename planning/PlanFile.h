// SPDX-License-Identifier: Apache-2.0
/// @file PlanFile.h
/// @brief Plan files, read and written in one place: the planned needle paths
/// that `voxhap view` and `voxhap render` draw, `serve --guide` pulls toward
/// and Python reads. Three kinds are read, told apart by their content:
///
/// - **voxhap-plan/1** (plan.json; written by savePlan, the viewer's `s`), all
///   points in patient LPS millimetres:
///   @code
///   {"schema": "voxhap-plan/1",
///    "paths": [{"name": "L3 biopsy", "entry": [x, y, z], "target": [x, y, z],
///               "needle": {"tip": [x, y, z], "direction": [x, y, z], "length_mm": 90}}]}
///   @endcode
///   "name" and "needle" are optional; "direction" points from hub to tip; at
///   least one path.
/// - **voxhap-plan-report/1** (report.json, what `voxhap plan` writes;
///   planning/Report.h): its "paths" in rank order, path N named "path N"; an
///   empty "paths" (a search that found nothing) gives a plan without paths.
/// - **3D Slicer markups** (.mrk.json): each Line markup with two control
///   points becomes a path (first point the entry), RAS converted to LPS
///   (planning/Markups.h).
#pragma once

#include "core/Math.h"

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace voxhap::planning {

inline constexpr const char* kPlanSchema = "voxhap-plan/1";          ///< plan.json
inline constexpr const char* kReportSchema = "voxhap-plan-report/1"; ///< the report of `voxhap plan` (Report.h)

/// @brief Where the needle is: tip and shaft direction.
struct NeedlePose {
    Vec3d tip{0, 0, 0};       ///< [mm, LPS]
    Vec3d direction{0, 0, 1}; ///< unit, hub to tip
    double lengthMm = 90.0;   ///< shaft length drawn behind the tip [mm] (haptic::Needle's default)
    /// A bending needle's shaft, hub to tip (physics.md §9); empty: straight from hub() to tip.
    std::vector<Vec3d> shaft;
    Vec3d hub() const { return tip - lengthMm * direction; }
    /// @brief The shaft as segments: the bent polyline, or the one straight segment.
    std::vector<std::pair<Vec3d, Vec3d>> segments() const
    {
        std::vector<std::pair<Vec3d, Vec3d>> out;
        if (shaft.size() < 2) return {{hub(), tip}};
        for (std::size_t i = 1; i < shaft.size(); ++i) out.emplace_back(shaft[i - 1], shaft[i]);
        return out;
    }
};

struct PlannedPath {
    std::string name;
    Vec3d entry{0, 0, 0};  ///< skin entry [mm, LPS]
    Vec3d target{0, 0, 0}; ///< [mm, LPS]
    std::optional<NeedlePose> needle;
};

struct Plan {
    std::vector<PlannedPath> paths;
};

/// @brief Read any of the three kinds above.
/// @throw IoError if unreadable; ValueError naming the file and the field
Plan loadPlan(const std::filesystem::path& file);

/// @brief Parse plan JSON text of any of the three kinds; @p origin names it in error messages.
Plan parsePlan(std::string_view json, const std::string& origin);

/// @brief The plan as voxhap-plan/1 JSON text (what parsePlan reads back).
std::string planJson(const Plan& plan);

/// @brief Write the plan as voxhap-plan/1, atomically. @throw IoError naming the file
void savePlan(const Plan& plan, const std::filesystem::path& file);

} // namespace voxhap::planning
