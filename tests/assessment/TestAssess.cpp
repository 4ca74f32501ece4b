// SPDX-License-Identifier: Apache-2.0
/// @file TestAssess.cpp
/// @brief Reference ranges (the scene's over the defaults, with sources), the
/// per-metric verdicts at and beyond their bounds, and metrics.json refusals
/// (issue 23 item 3).

#include "assessment/Assess.h"
#include "core/Errors.h"

#include <gtest/gtest.h>

#include <string>

namespace voxhap::assessment {
namespace {

const ReferenceRange& rangeOf(const std::vector<ReferenceRange>& r, const std::string& metric)
{
    for (const auto& x : r) {
        if (x.metric == metric) return x;
    }
    throw std::runtime_error("no range for " + metric);
}

// senac-average's ranges: [S19] Fig. 4's 3 mm/s and Table I's 6 mm epidural space
// replace the defaults, and the dura must stay intact ([S19]); the rest keep theirs.
TEST(Assess, SceneRangesReplaceTheDefaults)
{
    const haptic::Scene s = haptic::loadScene("senac-average");
    const auto r = referenceRanges(&s);
    EXPECT_EQ(*rangeOf(r, "speed_mean_mm_per_s").max, 3.0);
    EXPECT_EQ(rangeOf(r, "speed_mean_mm_per_s").from, "scene senac-average");
    EXPECT_NE(rangeOf(r, "speed_mean_mm_per_s").source.find("[S19] Fig. 4"), std::string::npos);
    EXPECT_EQ(*rangeOf(r, "epidural_overshoot_mm").max, 6.0);
    EXPECT_EQ(*rangeOf(r, "success_dura_intact").min, 1.0);
    EXPECT_EQ(rangeOf(r, "success_dura_intact").from, "scene senac-average");
    // A lumbar puncture must cross the dura: there the dura's state is reported, not judged.
    const haptic::Scene lp = haptic::loadScene("lumbar-puncture");
    EXPECT_FALSE(rangeOf(referenceRanges(&lp), "success_dura_intact").min);
    const haptic::Scene o = haptic::loadScene("senac-overweight");
    EXPECT_EQ(*rangeOf(referenceRanges(&o), "epidural_overshoot_mm").max, 4.0); // [S19] Table I
    // Every range has a source, and every built-in scene names only known metrics.
    for (const auto& name : haptic::builtinSceneNames()) {
        const haptic::Scene sc = haptic::loadScene(name);
        for (const auto& x : referenceRanges(&sc)) EXPECT_FALSE(x.source.empty()) << name << " " << x.metric;
    }
}

TEST(Assess, SceneWithAnUnknownMetricIsRefusedNamingTheField)
{
    const std::string text = R"({"schema": "voxhap-scene/1", "name": "x", "model": "senac", "terms": {"tip": true},
        "assessment": {"speed_mm_per_s": {"max": 2, "source": "[chosen]"}}})";
    const haptic::Scene s = haptic::parseScene(text, "x.json");
    try {
        referenceRanges(&s);
        FAIL() << "an unknown metric was accepted";
    } catch (const ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("x.json: assessment.speed_mm_per_s: not a metric"), std::string::npos)
            << e.what();
    }
    const auto refused = [](const std::string& block, const std::string& what) {
        const std::string t = R"({"schema": "voxhap-scene/1", "name": "x", "model": "senac", "terms": {"tip": true},
            "assessment": )" +
            block + "}";
        try {
            haptic::parseScene(t, "x.json");
            ADD_FAILURE() << "accepted " << block;
        } catch (const ValueError& e) {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    };
    refused(R"({"pops": {"min": 3, "max": 2, "source": "s"}})", "x.json: assessment.pops.min: must not exceed max");
    refused(R"({"pops": {"max": 2}})", "x.json: assessment.pops.source: missing");
    refused(R"({"pops": {"source": "s"}})", "x.json: assessment.pops: give min, max or both");
    refused(R"({"pops": {"max": 2, "source": "s", "typo": 1}})", "x.json: assessment.pops.typo: unknown field");
}

// Bounds are inclusive: a value on the bound passes, one just beyond is flagged; a
// flag is read as 1/0; null is "not measured"; a metric without range is "no range".
TEST(Assess, VerdictsAtAndBeyondTheBounds)
{
    const haptic::Scene s = haptic::loadScene("senac-average");
    const auto ranges = referenceRanges(&s);
    nlohmann::json j = {{"scene", "senac-average"}, {"success_dura_intact", true}, {"bone_contacts", 0},
        {"speed_mean_mm_per_s", 3.0}, {"epidural_overshoot_mm", 6.0}, {"syrrate_per_m", nullptr}, {"pops", 4}};
    SessionAssessment a = assessSession(sessionMetricsFromJson(j, "m.json"), ranges);
    EXPECT_EQ(a.flagged(), 0);
    const auto verdict = [](const SessionAssessment& x, const std::string& m) {
        for (const auto& r : x.metrics) {
            if (r.range.metric == m) return r.verdict;
        }
        return Verdict::NotMeasured;
    };
    EXPECT_EQ(verdict(a, "speed_mean_mm_per_s"), Verdict::Pass);
    EXPECT_EQ(verdict(a, "syrrate_per_m"), Verdict::NotMeasured);
    EXPECT_EQ(verdict(a, "pops"), Verdict::NotJudged);
    j["speed_mean_mm_per_s"] = 3.0000001;
    j["success_dura_intact"] = false;
    a = assessSession(sessionMetricsFromJson(j, "m.json"), ranges);
    EXPECT_EQ(a.flagged(), 2);
    EXPECT_EQ(verdict(a, "speed_mean_mm_per_s"), Verdict::Flag);
    EXPECT_EQ(verdict(a, "success_dura_intact"), Verdict::Flag);
    EXPECT_EQ(toJson(a)["flagged"], 2);
}

TEST(Assess, BadMetricsAreRefusedNamingFileAndField)
{
    const auto refused = [](const nlohmann::json& j, const std::string& what) {
        try {
            sessionMetricsFromJson(j, "m.json");
            ADD_FAILURE() << "accepted " << j.dump();
        } catch (const ValueError& e) {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    };
    refused({{"scene", "kyung"}, {"pops", "three"}}, "m.json: pops: must be a finite number");
    refused({{"pops", 3}}, "m.json: scene: missing");
    refused({{"scene", "kyung"}, {"ticks", 3}}, "m.json: no trainee metrics");
}

// The metrics are named, measured and written by haptic/servo/TraineeMetrics.h;
// assessment/ only judges them: each judged key is one the catalogue names.
TEST(Metrics, EveryJudgedMetricIsOneTheSessionComputes)
{
    for (const DefaultRange& r : defaultRanges())
        EXPECT_NE(haptic::findTraineeMetric(r.key), nullptr) << r.key << " is judged but no session computes it";
    EXPECT_EQ(haptic::findTraineeMetric("speed_mean"), nullptr); // a key the catalogue does not hold
}

TEST(Metrics, MetricsJsonHoldsEachFieldUnderItsNameAndKind)
{
    // Every field distinct, so that a key wired to the wrong field shows.
    haptic::TraineeMetrics m;
    m.success = false;
    m.duraIntact = true;
    m.boneContacts = 2;
    m.pops = 5;
    m.insertionAngleDeg = 3.25;
    m.speedMeanMmPerS = 1.5;
    m.speedVarianceMm2PerS2 = 0.75;
    m.overshootMm = std::nullopt; // not measured: null
    m.syrrate = 11.5;
    m.durationS = 42.5;
    m.poseFaults = 7;
    m.forceLimits = 4;
    m.outcome.targetDistanceMm = 6.5;
    m.outcome.csfReached = true;
    m.outcome.criticalBreach = false;
    m.outcome.reason = "why";
    const nlohmann::json j = traineeMetricsJson(m);
    const nlohmann::json expected = {{"success", false}, {"success_dura_intact", true}, {"bone_contacts", 2},
        {"pops", 5}, {"insertion_angle_deg", 3.25}, {"speed_mean_mm_per_s", 1.5}, {"speed_variance_mm2_per_s2", 0.75},
        {"epidural_overshoot_mm", nullptr}, {"syrrate_per_m", 11.5}, {"duration_s", 42.5}, {"pose_faults", 7},
        {"force_limited", 4}, {"target_distance_mm", 6.5}, {"csf_reached", true}, {"critical_breach", false},
        {"success_rule", haptic::successRuleName(m.outcome.rule)}, {"success_reason", "why"}};
    EXPECT_EQ(j, expected);
    // Counts are whole numbers in the file ("5", not "5.0"), as before the catalogue moved.
    EXPECT_EQ(j.at("pops").dump(), "5");
    EXPECT_TRUE(j.at("pose_faults").is_number_integer());
}

} // namespace
} // namespace voxhap::assessment
