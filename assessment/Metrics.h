// SPDX-License-Identifier: Apache-2.0
/// @file Metrics.h
/// @brief The trainee metrics `voxhap assess` judges, with their default
/// reference ranges and each range's source, and metrics.json written and read
/// back. What each metric is called, its unit and how it is computed is
/// haptic/servo/TraineeMetrics.h's (physics.md §2.3).
#pragma once

#include "haptic/servo/TraineeMetrics.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace voxhap::assessment {

/// @brief One assessed metric (a key of haptic::traineeMetricCatalogue()) and its
/// default reference range, used where the scene gives none.
struct DefaultRange {
    std::string key;
    std::optional<double> min, max; ///< neither: reported, not judged
    std::string source;             ///< of the range
};

/// @brief Every metric `voxhap assess` judges, in report order.
const std::vector<DefaultRange>& defaultRanges();

/// @brief The trainee metrics as metrics.json writes them: every metric of the
/// catalogue (a flag true/false, a count a whole number, a value not measured
/// null), the success rule's name and its reason.
nlohmann::json traineeMetricsJson(const haptic::TraineeMetrics& m);

/// @brief One session's metrics, read back.
struct SessionMetrics {
    std::string file;  ///< for messages and reports
    std::string scene; ///< metrics.json "scene"
    /// Every catalogue metric present in the file: a number, a flag as 1/0, or
    /// nullopt where the file holds null (not measured in that session).
    std::map<std::string, std::optional<double>> values;
};

/// @brief Read a metrics.json. @throw IoError, ValueError naming the file and the field
SessionMetrics readSessionMetrics(const std::filesystem::path& file);
/// @brief The same from parsed JSON; @p origin names it in messages.
SessionMetrics sessionMetricsFromJson(const nlohmann::json& j, const std::string& origin);

/// @brief The metrics.json files @p inputs name: a file as given, a folder
/// searched recursively for files named metrics.json (sorted by path).
/// @throw IoError naming an input that does not exist or a folder without any
std::vector<std::filesystem::path> findSessionFiles(const std::vector<std::string>& inputs);

} // namespace voxhap::assessment
