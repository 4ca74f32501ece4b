// SPDX-License-Identifier: Apache-2.0
/// @file TestSimulatedCohort.cpp
/// @brief A simulated cohort (careful and reckless simulated hands with varied
/// speed, grip and reaction time on senac-average) through the assessment: every
/// careful simulated hand passes every range, every reckless one is flagged, and
/// the classifier tells them apart under cross-validation. Simulated hands only:
/// nothing here is about real trainees (issue 23 item 3).

#include "assessment/Assess.h"
#include "assessment/Classifier.h"
#include "assessment/SimulatedCohort.h"
#include "volume/TissueTable.h"

#include <gtest/gtest.h>

#include <string>

namespace voxhap::assessment {
namespace {

struct SimulatedCohortRun {
    std::vector<SimulatedTrainee> trainees;
    std::vector<nlohmann::json> sessions;
};

const SimulatedCohortRun& simulated()
{
    static const SimulatedCohortRun run = [] {
        SimulatedCohortRun r;
        const haptic::SceneInstance inst(haptic::loadScene("senac-average"), nullptr, volume::TissueTable::builtin());
        CohortSpec spec;
        spec.perClass = 6;
        r.trainees = simulatedCohort(spec);
        for (const auto& t : r.trainees) r.sessions.push_back(simulateSession(inst, t));
        return r;
    }();
    return run;
}

TEST(SimulatedCohort, CarefulSimulatedHandsPassRecklessOnesAreFlagged)
{
    const haptic::Scene scene = haptic::loadScene("senac-average");
    const auto ranges = referenceRanges(&scene);
    const auto& run = simulated();
    ASSERT_EQ(run.sessions.size(), 12u);
    for (std::size_t i = 0; i < run.sessions.size(); ++i) {
        const nlohmann::json& j = run.sessions[i];
        EXPECT_TRUE(j["simulated"].get<bool>());
        EXPECT_EQ(j["dropped_records"], 0);
        const SessionAssessment a = assessSession(sessionMetricsFromJson(j, j["trainee"].get<std::string>()), ranges);
        if (run.trainees[i].careful) {
            EXPECT_EQ(a.flagged(), 0) << toJson(a).dump(1);
            EXPECT_TRUE(j["success_dura_intact"].get<bool>()) << j.dump(1);
        } else {
            EXPECT_GT(a.flagged(), 0) << toJson(a).dump(1);
            EXPECT_FALSE(j["success_dura_intact"].get<bool>())
                << j.dump(1); // the simulated hand went on through the dura
        }
    }
}

// The speeds differ by construction (careful 0.5-2 mm/s, reckless 2.5-8 mm/s); the
// mean advancing speed each simulated session measured must reflect it.
TEST(SimulatedCohort, MeasuredSpeedFollowsTheSimulatedHand)
{
    const auto& run = simulated();
    for (std::size_t i = 0; i < run.sessions.size(); ++i) {
        const double v = run.sessions[i]["speed_mean_mm_per_s"].get<double>();
        if (run.trainees[i].careful)
            EXPECT_LE(v, 2.0 + 0.5) << run.trainees[i].id; // the hand lags and springs, never far past its set point
        else
            EXPECT_GE(v, 2.5 - 0.5) << run.trainees[i].id;
    }
}

// Trained on the simulated sessions' metrics (label 1 = reckless), 3-fold
// cross-validated accuracy is above chance: the Wilson 95 % interval's lower bound
// exceeds 0.5. The simulated hands differ by construction (disjoint speed ranges),
// so this shows that the metrics carry the difference through simulate, the
// session files and the assessment, not how good the classifier is: that is
// CrossValidation.OverlappingClassesReachTheBayesAccuracyOnHeldOutFolds.
TEST(SimulatedCohort, ClassifierSeparatesSimulatedHandsUnderCrossValidation)
{
    const auto& run = simulated();
    LabelledSet d;
    d.origin = "simulated cohort";
    d.features = {"speed_mean_mm_per_s", "speed_variance_mm2_per_s2", "epidural_overshoot_mm", "bone_contacts"};
    for (std::size_t i = 0; i < run.sessions.size(); ++i) {
        std::vector<double> row;
        for (const auto& f : d.features) {
            const auto& v = run.sessions[i][f];
            row.push_back(v.is_null() ? 0.0 : v.get<double>());
        }
        d.x.push_back(row);
        d.y.push_back(run.trainees[i].careful ? 0 : 1);
    }
    const CrossValidation cv = crossValidate(d, 3);
    EXPECT_GT(cv.ci95.low, 0.5) << cv.correct << "/" << cv.n;
}

} // namespace
} // namespace voxhap::assessment
