// SPDX-License-Identifier: Apache-2.0
/// @file Report.h
/// @brief The planning report as JSON ("voxhap-plan-report/1", docs/reference.md "Planning"):
///
/// @code
/// {"schema": "voxhap-plan-report/1",
///  "volume": "...", "scene": "kyung", "speed_mm_per_s": 10, "needle_mm": 150, "device": {...},
///  "risk_formula": "...",
///  "paths": [ <path>, ... ],              // the analysed path, or the ranked candidates
///  "pareto": [ <path>, ... ],             // search only
///  "search": {"directions": n, "analysed": n, "feasible": n, "rejected": {...}, "seconds": s}}
/// <path> = {"rank": 1, "entry": [x,y,z], "target": [x,y,z], "length_mm": l, "target_tissue": "lesion",
///           "segments": [{"tissue": "skin", "start_mm": 0, "end_mm": 2, "length_mm": 2, "critical": false, "rigid":
///           false}], "clearances": [{"structure": "kidney", "min_mm": 12.5, "at_mm": 40, "at_least": false}],
///           "min_clearance_mm": 12.5, "nearest_structure": "kidney",
///           "bone": {"entries": 1, "obstacles": 0, "first_mm": 55},
///           "force": {"peak_N": 3.1, "peak_depth_mm": 50, "contact_mm": 55, "depth_mm": [...], "force_N": [...]},
///           "warnings": [{"code": "...", "message": "..."}],
///           "risk": {"total": 1.2, "breach": 0, "too_short": 0, "bone_obstacles": 0, "over_force": 0,
///                    "proximity": 0.4, "length": 0.5, "force": 0.3}}
/// @endcode
/// Points are LPS millimetres. "at_least": the structure lies beyond the distance
/// field's band, so the clearance is at least min_mm.
#pragma once

#include "planning/Markups.h"
#include "planning/PlanFile.h"
#include "planning/Search.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace voxhap::planning {

inline constexpr const char* kRiskFormula =
    "R = 100*breach + 100*too_short + 10*bone_obstacles + 10*over_force + sum_c max(0, 1 - clearance_c/margin) "
    "+ length/needle_length + peak_force/device_peak_force";

nlohmann::json pathJson(const TrajectoryReport& r, int rank);
/// @brief The report's header: volume name, scene, speed, needle, device, margin, formula.
nlohmann::json reportHeader(const Planner& planner, const std::string& volumeName);

/// @brief The "search" block of a report: counts, rejections by reason, time and the constraints used.
nlohmann::json searchJson(
    const Planner& planner, const SearchResult& found, const SearchConstraints& k, const SearchOptions& options);
/// @brief Write @p report atomically (core/AtomicFile.h). @throw IoError
/// (Its paths are read back by planning/PlanFile.h, with every other plan file.)
void writeReport(const nlohmann::json& report, const std::filesystem::path& file);

} // namespace voxhap::planning
