// SPDX-License-Identifier: Apache-2.0
/// @file Assess.cpp
/// @brief Reference ranges and the per-metric verdicts.

#include "assessment/Assess.h"

#include "core/Errors.h"

#include <algorithm>

namespace voxhap::assessment {

std::vector<ReferenceRange> referenceRanges(const haptic::Scene* scene)
{
    std::vector<ReferenceRange> out;
    for (const DefaultRange& m : defaultRanges()) out.push_back({m.key, m.min, m.max, m.source, "default"});
    if (!scene) return out;
    for (const haptic::MetricRange& r : scene->assessment) {
        const auto it =
            std::find_if(out.begin(), out.end(), [&](const ReferenceRange& x) { return x.metric == r.metric; });
        if (it == out.end()) {
            std::string names;
            for (const DefaultRange& m : defaultRanges()) names += (names.empty() ? "" : ", ") + m.key;
            throw ValueError(
                scene->origin + ": assessment." + r.metric + ": not a metric of metrics.json (" + names + ")");
        }
        *it = {r.metric, r.min, r.max, r.source, "scene " + scene->name};
    }
    return out;
}

const char* verdictName(Verdict v)
{
    switch (v) {
    case Verdict::Pass:
        return "pass";
    case Verdict::Flag:
        return "flag";
    case Verdict::NotJudged:
        return "no range";
    case Verdict::NotMeasured:
        return "not measured";
    }
    return "?";
}

int SessionAssessment::flagged() const
{
    return int(std::count_if(
        metrics.begin(), metrics.end(), [](const MetricResult& m) { return m.verdict == Verdict::Flag; }));
}

int SessionAssessment::passed() const
{
    return int(std::count_if(
        metrics.begin(), metrics.end(), [](const MetricResult& m) { return m.verdict == Verdict::Pass; }));
}

SessionAssessment assessSession(const SessionMetrics& s, const std::vector<ReferenceRange>& ranges)
{
    SessionAssessment a;
    a.file = s.file;
    a.scene = s.scene;
    for (const ReferenceRange& r : ranges) {
        MetricResult m;
        m.range = r;
        const auto it = s.values.find(r.metric);
        if (it != s.values.end()) m.value = it->second;
        if (!m.value) {
            m.verdict = Verdict::NotMeasured;
        } else if (!r.min && !r.max) {
            m.verdict = Verdict::NotJudged;
        } else {
            const bool below = r.min && *m.value < *r.min;
            const bool above = r.max && *m.value > *r.max;
            m.verdict = below || above ? Verdict::Flag : Verdict::Pass;
        }
        a.metrics.push_back(std::move(m));
    }
    return a;
}

nlohmann::json toJson(const SessionAssessment& a)
{
    nlohmann::json metrics = nlohmann::json::array();
    const auto opt = [](const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); };
    for (const MetricResult& m : a.metrics) {
        const haptic::TraineeMetricInfo* info = haptic::findTraineeMetric(m.range.metric);
        metrics.push_back({{"metric", m.range.metric}, {"value", opt(m.value)},
            {"unit", info ? std::string(info->unit) : std::string()}, {"min", opt(m.range.min)},
            {"max", opt(m.range.max)}, {"verdict", verdictName(m.verdict)}, {"source", m.range.source},
            {"range_from", m.range.from}});
    }
    return {{"file", a.file}, {"scene", a.scene}, {"flagged", a.flagged()}, {"passed", a.passed()},
        {"metrics", std::move(metrics)}};
}

std::vector<double> modelFeatures(const SessionMetrics& s, const LogisticModel& m, const std::string& modelName)
{
    std::vector<double> x;
    for (const std::string& f : m.features) {
        const auto it = s.values.find(f);
        if (it == s.values.end() || !it->second)
            throw ValueError(
                s.file + ": " + f + ": not measured in this session, and the model " + modelName + " needs it");
        x.push_back(*it->second);
    }
    return x;
}

} // namespace voxhap::assessment
