// SPDX-License-Identifier: Apache-2.0
/// @file Metrics.h
/// @brief The trainee metrics a session leaves in metrics.json (`voxhap serve`;
/// haptic/servo/Session.h computes them, physics.md §2.3), their units and
/// default reference ranges, and reading them back from one or many sessions.
#pragma once

#include "haptic/servo/Session.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace voxhap::assessment {

/// @brief One assessable metric: its metrics.json key, unit, meaning and the
/// default reference range (used where the scene gives none).
struct MetricInfo {
    std::string key;
    std::string unit; ///< "" for counts; "true/false" for a flag (read as 1/0)
    std::string description;
    std::optional<double> min, max; ///< default range; neither: reported, not judged
    std::string source;             ///< of the default range
};

/// @brief Every metric `voxhap assess` knows, in report order.
const std::vector<MetricInfo>& metricCatalogue();
/// @brief The catalogue entry of @p key, or null.
const MetricInfo* findMetric(std::string_view key);

/// @brief The trainee metrics as metrics.json writes them (the keys of the catalogue
/// that a session computes; a metric without a value is null).
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
