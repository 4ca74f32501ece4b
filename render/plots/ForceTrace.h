// SPDX-License-Identifier: Apache-2.0
/// @file ForceTrace.h
/// @brief Force against tip depth, with the layers crossed and the events:
/// what the force–depth plot draws, from a simulated insertion in memory or
/// from a recording on disk (`voxhap simulate`'s insertion.csv, `voxhap
/// serve`'s session.csv with events.csv beside it).
#pragma once

#include "haptic/scene/ScriptedInsertion.h"

#include <filesystem>
#include <string>
#include <vector>

namespace voxhap::render {

struct ForceTrace {
    struct Sample {
        double depthMm = 0;   ///< tip depth along the path [mm]
        double renderedN = 0; ///< |F| sent to the device [N]
        double axialN = 0;    ///< the model's resistance along the path [N]
        double plungerN = 0;  ///< syringe plunger force [N]
    };
    struct Band {
        std::string name; ///< tissue or table row
        double startMm = 0, endMm = 0;
    };
    struct Mark {
        double depthMm = 0;
        std::string text; ///< event names at this depth, comma-separated
    };
    std::string title;
    std::vector<Sample> samples;
    std::vector<Band> layers; ///< in the order met along the path
    std::vector<Mark> events; ///< skin contact and critical clear left out (they only restate others)

    /// @brief Add an event at @p depthMm (merged with the previous one at the same depth).
    void addEvent(double depthMm, const std::string& name);
};

/// @brief The trace of a simulated insertion; bands are the model's layers (air left out).
ForceTrace forceTrace(
    const haptic::InsertionResult& r, const std::vector<haptic::Layer>& layers, const std::string& title);

/// @brief Read a recording: an insertion.csv, a session.csv (its events.csv
/// beside it is read too), or a folder holding one of them. Bands come from the
/// runs of the layer column (where the tip was).
/// @throw IoError if unreadable, ValueError naming the file, line and column
ForceTrace readForceTrace(const std::filesystem::path& path);

} // namespace voxhap::render
