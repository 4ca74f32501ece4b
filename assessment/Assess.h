// SPDX-License-Identifier: Apache-2.0
/// @file Assess.h
/// @brief A session's metrics against reference ranges: pass or flag per metric.
/// The ranges are the scene's ("assessment" block of a scene
/// file) over the defaults (Metrics.h), each with its source.
#pragma once

#include "assessment/Classifier.h"
#include "assessment/Metrics.h"
#include "haptic/scene/Scene.h"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace voxhap::assessment {

/// @brief The range one metric is judged against, and where it comes from.
struct ReferenceRange {
    std::string metric;
    std::optional<double> min, max; ///< inclusive; neither: reported, not judged
    std::string source;
    std::string from; ///< "scene <name>" or "default"
};

/// @brief The catalogue's defaults, replaced metric by metric by @p scene's ranges.
/// @throw ValueError naming the scene's origin and "assessment.<name>" for a metric
/// the catalogue does not know
std::vector<ReferenceRange> referenceRanges(const haptic::Scene* scene);

enum class Verdict {
    Pass,       ///< within the range
    Flag,       ///< outside it
    NotJudged,  ///< no range for this metric
    NotMeasured ///< the session holds null or lacks the metric
};
const char* verdictName(Verdict v);

struct MetricResult {
    ReferenceRange range;
    std::optional<double> value;
    Verdict verdict = Verdict::NotJudged;
};

struct SessionAssessment {
    std::string file, scene;
    std::vector<MetricResult> metrics; ///< in catalogue order
    int flagged() const;
    int passed() const;
};

/// @brief Judge @p s against @p ranges.
SessionAssessment assessSession(const SessionMetrics& s, const std::vector<ReferenceRange>& ranges);

/// @brief {"file", "scene", "flagged", "metrics": [{"metric", "value", "unit", "min", "max", "verdict", "source",
/// "range_from"}]}
nlohmann::json toJson(const SessionAssessment& a);

/// @brief The features @p m reads, from a session's metrics, in the model's order.
/// @throw ValueError naming the session's file and a feature it did not measure (and @p modelName)
std::vector<double> modelFeatures(const SessionMetrics& s, const LogisticModel& m, const std::string& modelName);

} // namespace voxhap::assessment
