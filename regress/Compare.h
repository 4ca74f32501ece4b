// SPDX-License-Identifier: Apache-2.0
/// @file Compare.h
/// @brief Baselines (data/regress/<case>.json: profile, events, peaks and the
/// fingerprint of every input) and the comparison of a run with its baseline
/// and, where physics.md §7 has one, its closed form.
#pragma once

#include "regress/CaseRunner.h"

#include <nlohmann/json_fwd.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::regress {

struct Baseline {
    std::string file;
    Inputs inputs;
    Profile profile;
};

/// @brief The baseline file of case @p name in @p dir.
std::filesystem::path baselinePath(const std::filesystem::path& dir, const std::string& name);
/// @brief Read a baseline; nothing when the file does not exist.
/// @throw ValueError "file: field: why" when it is unreadable, truncated or malformed
std::optional<Baseline> readBaseline(const std::filesystem::path& file);
/// @brief Parse a baseline's text (the built-in ones compiled into the binary);
/// errors name @p origin. @throw ValueError
Baseline parseBaseline(const std::string& text, const std::string& origin);
/// @brief The JSON a baseline file holds.
nlohmann::json baselineJson(const Case& c, const CaseRun& run);
/// @brief A baseline as its file holds it: one input per line (they are what a
/// reader compares), each profile column and the events on one line.
std::string baselineText(const nlohmann::json& doc);

/// @brief A failing comparison's first point: where, against what, in which tissue.
struct Exceedance {
    double depthMm = 0;
    double deltaN = 0, toleranceN = 0;
    std::string against; ///< "baseline" or the closed form's rule
    std::string tissue;  ///< the layer at that depth, or "outside the body"
};

/// @brief The verdict on one case.
struct CaseReport {
    std::string name;
    bool pass = false;
    bool hasBaseline = false;
    bool identical = false; ///< the digest matches the baseline's: bit for bit on every tick
    std::string reference;  ///< "baseline", "baseline + physics.md §7 R1 (...)"
    double maxDeltaN = 0;   ///< largest |ΔF| against the baseline (or the closed form without one) [N]
    double maxDeltaDepthMm = 0;
    std::optional<Exceedance> first;     ///< first depth past a tolerance
    std::vector<std::string> eventDiffs; ///< "pop count 3 → 4", "pop #2 depth 12.35 → 12.50 mm"
    std::vector<std::string> peakDiffs;
    std::vector<std::string> inputDiffs; ///< "skin.cutting_force 2 → 2.1 N"
    std::optional<double> closedFormMaxDeltaN;
    std::optional<double> tipDeviationMm; ///< a bending needle's, at the last tick [mm]
    /// Against the case's measured deflection: "5.00 mm measured (source), model
    /// 6.10 mm, +22 %, tolerance 1.50 mm"; empty without one.
    std::string measured;
    bool measuredPass = true;
    std::string closedForm;  ///< "closed form: R1", or "no closed form: <why>" (ClosedFormCheck::line)
    std::string digest;      ///< of this run's profile (CaseRunner.h)
    std::string png;         ///< the failing case's plot, when drawn
    std::string plotProblem; ///< why it was not drawn (gnuplot missing or failing)
    double seconds = 0;
};

/// @brief Compare @p run with @p baseline (when there is one) and with the
/// case's closed form (evaluated with the baseline's recorded values).
CaseReport compareCase(const Case& c, const CaseRun& run, const std::optional<Baseline>& baseline);

/// @brief "key old → new unit" for each input that differs (added and removed ones too).
std::vector<std::string> inputDifferences(const Inputs& before, const Inputs& now);

} // namespace voxhap::regress
