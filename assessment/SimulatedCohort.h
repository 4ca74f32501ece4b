// SPDX-License-Identifier: Apache-2.0
/// @file SimulatedCohort.h
/// @brief Simulated trainees for testing the assessment: careful and reckless
/// simulated hands (haptic/devices/SimulatedDevices.h) with varied speed, grip and
/// reaction time, each run through a scene's force model in simulated time, giving
/// the metrics.json fields `voxhap serve` writes.
///
/// These are simulated hands, not people: a cohort made here says how the
/// assessment separates two kinds of simulated hand, and nothing about real
/// trainees.
#pragma once

#include "haptic/devices/SimulatedDevices.h"
#include "haptic/scene/Scene.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace voxhap::assessment {

/// @brief One simulated trainee.
struct SimulatedTrainee {
    std::string id;      ///< "careful-03", "reckless-11"
    bool careful = true; ///< label 0 careful, 1 reckless
    haptic::HandParams hand;
    double seconds = 60; ///< simulated session length [s]
};

/// @brief How the two kinds of simulated hand differ [chosen]. Careful: set-point
/// speed uniform in [carefulMin, carefulMax] mm/s, stops a reaction time after the
/// loss of resistance. Reckless: [recklessMin, recklessMax] mm/s and does not stop
/// on it. Both draw the grip in [0.8, 1.4] N/mm (damping critical for it) and the
/// reaction time in [0.15, 0.35] s.
struct CohortSpec {
    int perClass = 10;
    double carefulMinMmPerS = 0.5, carefulMaxMmPerS = 2.0;
    double recklessMinMmPerS = 2.5, recklessMaxMmPerS = 8.0;
    double approachMm = 5.0; ///< the hands start this far outside the entry
    /// The set point stops here: 80 mm, the hand's default, puts a reckless hand's
    /// grip (≥ 0.8 N/mm over the ~40 mm past the dura) above the 16 N of nested
    /// cutting plus the dura's 8 N in the senac scenes.
    double maxDepthMm = 80.0;
    unsigned seed = 7; ///< mt19937
};

/// @brief perClass careful trainees, then perClass reckless ones.
std::vector<SimulatedTrainee> simulatedCohort(const CohortSpec& spec);

/// @brief Run @p t through @p inst's force model at the scene's servo rate in
/// simulated time; the result has the keys of serve's metrics.json ("scene",
/// "device": "sim-hand", the trainee metrics, "simulated": true, "trainee": id).
nlohmann::json simulateSession(const haptic::SceneInstance& inst, const SimulatedTrainee& t);

/// @brief `voxhap assess --simulate-cohort`: @p perClass careful and as many
/// reckless simulated hands on @p scene, written as @p out/<id>/metrics.json and
/// @p out/labelled.csv (label 1 reckless; the columns: every assessed metric all
/// sessions measured, but the duration and pose faults, which are not skill),
/// together. @return {"simulated_cohort": {scene, sessions, labelled_csv, note}}
/// @throw IoError naming the file
nlohmann::json writeSimulatedCohort(
    const haptic::Scene& scene, const volume::TissueTable& table, int perClass, const std::filesystem::path& out);

} // namespace voxhap::assessment
