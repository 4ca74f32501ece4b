// SPDX-License-Identifier: Apache-2.0
/// @file Guide.h
/// @brief `--guide FILE --guide-path N` of `voxhap simulate` and `voxhap serve`: the
/// planned line guidance pulls toward (haptic/force/Guidance.h), read from the
/// report or the markups `voxhap plan` wrote, or a plan.json (planning/PlanFile.h).
#pragma once

#include "haptic/force/Guidance.h"

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

namespace voxhap::tools {

struct GuideOptions {
    std::string file; ///< report.json or .mrk.json; empty: no guidance from a plan
    int path = 1;     ///< 1-based: the report's rank, the markups' Line
};

/// @brief Add --guide and --guide-path to @p cmd.
void addGuideOptions(CLI::App& cmd, GuideOptions& o);

/// @brief The planned line the options name, or nothing without --guide.
/// @throw UsageError for --guide-path without --guide; IoError, ValueError naming
/// the file and the field (a path number beyond the file's paths included)
std::optional<haptic::GuideLine> guideLine(const GuideOptions& o, const CLI::App& cmd);

/// @brief One line for a command's summary: where the guide came from.
std::string guideDescription(const GuideOptions& o, const haptic::GuideLine& line);

} // namespace voxhap::tools
