// SPDX-License-Identifier: Apache-2.0
/// @file ServoBench.h
/// @brief The servo-loop figures of benchmarks.md: a real-time loop with the
/// simulated hand for N seconds (tick compute median, p99, max; period error;
/// overruns), and the highest rate the loop sustains.
#pragma once

#include "core/Progress.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace voxhap::bench {

struct ServoBenchOptions {
    std::vector<std::string> scenes{"senac-average", "kyung"};
    double seconds = 30.0;                                             ///< the 1 kHz run
    std::vector<double> rates{1e3, 2e3, 5e3, 10e3, 20e3, 50e3, 100e3}; ///< the rate ladder [Hz]
    double ladderSeconds = 2.0;
    double igtlSeconds = 10.0; ///< the OpenIGTLink round-trip run
};

struct ServoRun {
    std::string scene;
    double rateHz = 0, seconds = 0, achievedHz = 0;
    long ticks = 0, overruns = 0;
    double computeP50Ns = 0, computeP99Ns = 0, computeMaxNs = 0;
    double periodErrP50Ns = 0, periodErrP99Ns = 0;
};

/// @brief OpenIGTLink pose → force round trip on loopback, the servo running.
struct IgtlRoundTrip {
    long samples = 0, lost = 0;
    double p50Us = 0, p99Us = 0, maxUs = 0;
};

struct ServoReport {
    std::string machine;
    std::vector<ServoRun> runs;                                ///< the long run at 1 kHz, per scene
    std::vector<ServoRun> ladder;                              ///< per scene and rate
    std::vector<std::pair<std::string, double>> sustainableHz; ///< per scene
    IgtlRoundTrip igtl;                                        ///< at 1 kHz on the first scene
};

ServoReport runServoBench(const ServoBenchOptions& o, const Progress& progress = {});
void printServoReport(std::ostream& os, const ServoReport& r);
nlohmann::json servoReportJson(const ServoReport& r);

} // namespace voxhap::bench
