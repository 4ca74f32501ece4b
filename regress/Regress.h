// SPDX-License-Identifier: Apache-2.0
/// @file Regress.h
/// @brief A regression run from end to end (`voxhap regress`): select the cases,
/// run them, compare each with its baseline and closed form, explain and plot
/// the failures, and with --update write the baselines; then the report as a
/// terminal table, JSON and JUnit XML.
#pragma once

#include "regress/Compare.h"

#include <nlohmann/json_fwd.hpp>

#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

namespace voxhap::regress {

struct RegressOptions {
    RunOptions run;
    std::string only;              ///< --only PATTERN; empty: every case
    bool update = false;           ///< write the baselines (atomically) and list what changed
    std::filesystem::path plotDir; ///< PNGs of failing cases; empty: none
};

struct RegressResult {
    std::string suite;
    std::vector<CaseReport> cases;
    std::vector<std::string> updated; ///< with --update: "name: new", "name: inputs changed (…)", ...
    std::string updateDir;            ///< with --update: the folder the baselines are written to
    double seconds = 0;               ///< wall time of the run (volumes, cases, comparison)
    double volumeSeconds = 0;         ///< of which building the shared volumes
    std::size_t volumes = 0;          ///< distinct volumes built
    int threads = 0;
    std::size_t failed() const;
};

/// @brief Run @p suite. @throw ValueError, IoError on a bad suite or input (exit 2)
RegressResult runRegression(const Suite& suite, const RegressOptions& options);

/// @brief The terminal report: one row per case, then the explanation of each failure.
void printReport(std::ostream& os, const RegressResult& r);
/// @brief The machine-readable report (`--json`).
nlohmann::json reportJson(const RegressResult& r);
/// @brief JUnit XML: one testsuite, one testcase per case, a failure element for each failing one.
std::string junitXml(const RegressResult& r);

/// @brief The plot of a failing case: reference and now against depth, the
/// difference below, the layers along the path shaded and named.
/// @return false with @p why set when gnuplot is missing or fails
bool plotCase(const CaseReport& report, const CaseRun& run, const std::vector<Sample>& reference,
    const std::string& referenceName, const std::string& pngFile, std::string& why);

} // namespace voxhap::regress
