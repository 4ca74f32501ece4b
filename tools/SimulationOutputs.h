// SPDX-License-Identifier: Apache-2.0
/// @file SimulationOutputs.h
/// @brief What a simulated insertion leaves behind: insertion.csv, summary.json and
/// force-depth.png in one directory (`voxhap simulate`, `voxhap demo`).
#pragma once

#include "haptic/scene/Scene.h"
#include "haptic/scene/ScriptedInsertion.h"

#include <nlohmann/json.hpp>

#include <ostream>
#include <string>

namespace voxhap::tools {

struct SimulationFiles {
    std::string csv, json, png; ///< png is empty when not plotted
    bool plotted = false;
    std::string plotWhy; ///< why there is no plot
    nlohmann::json summary;
};

/// @brief Write the CSV, the JSON summary and (when @p plot) the PNG into @p outDir.
/// @throw IoError when a file cannot be written; a missing gnuplot only skips the PNG
SimulationFiles writeSimulation(
    const haptic::InsertionResult& r, const haptic::SceneInstance& inst, const std::string& outDir, bool plot);

/// @brief One line per output file, indented.
void printOutputs(std::ostream& os, const SimulationFiles& f);

} // namespace voxhap::tools
