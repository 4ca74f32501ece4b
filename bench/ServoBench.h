// SPDX-License-Identifier: Apache-2.0
/// @file ServoBench.h
/// @brief The servo-loop figures of benchmarks.md: a real-time loop with the
/// simulated hand for N seconds (tick compute median, p99, max; period error;
/// overruns), and the highest rate the loop sustains.
#pragma once

#include "core/Progress.h"
#include "haptic/servo/ServoLoop.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace voxhap::bench {

struct ServoBenchOptions {
    /// The bending scenes beside their straight twins (physics.md §9.4), in one run.
    std::vector<std::string> scenes{
        "senac-average", "kyung", "kyung-bending", "lumbar-puncture", "lumbar-puncture-bending"};
    double seconds = 30.0;                                             ///< the 1 kHz run
    std::vector<double> rates{1e3, 2e3, 5e3, 10e3, 20e3, 50e3, 100e3}; ///< the rate ladder [Hz]
    double ladderSeconds = 2.0;
    int ladderRepeats = 1;     ///< full ladders per scene; the highest sustained rate reported is their median
    double igtlSeconds = 10.0; ///< the OpenIGTLink round-trip run
    /// CPU-bound processes (a busy loop each, normal priority, like `yes > /dev/null`)
    /// running beside the loop for the whole benchmark.
    int load = 0;
    bool realtime = true; ///< ask for SCHED_FIFO and locked memory (ServoOptions::realtime)
    int repeats = 1;      ///< 1 kHz runs per scene; the report gives each and their median
    int catchUpPeriods = haptic::ServoOptions{}.catchUpPeriods; ///< ServoOptions::catchUpPeriods
    bool align = true;                                          ///< ServoOptions::alignToInterruptions
    int pinCpu = -1;                                            ///< ServoOptions::pinCpu
    double floorSeconds = 10.0;                                 ///< the interruption probe before the scenes (0: none)
};

struct ServoRun {
    std::string scene;
    double rateHz = 0, seconds = 0, achievedHz = 0; ///< achieved: ticks over the first-to-last-tick window
    double startS =
        0; ///< wall time of the run outside that window: set-up before the first tick, the stop after the last
    long ticks = 0, overruns = 0;
    long skipped = 0;    ///< periods dropped after stalls longer than the catch-up bound
    double phaseUs = -1; ///< the interruption phase the grid was aligned to [us into the period]; -1: not aligned
    double computeP50Ns = 0, computeP99Ns = 0, computeMaxNs = 0;
    double periodErrP50Ns = 0, periodErrP99Ns = 0;
    bool realtime = false; ///< SCHED_FIFO was granted
    double stealS = 0;     ///< host steal time during the run, all CPUs [s] (/proc/stat)
};

/// @brief How often the machine itself takes the CPU from a real-time thread that does
/// nothing but read the clock: the floor under any loop's overruns. A loop at rate R
/// whose tick takes c overruns at least whenever such a gap exceeds 1/R − c.
struct InterruptionFloor {
    double seconds = 0;
    bool realtime = false;                                ///< the probe ran under SCHED_FIFO
    std::vector<std::pair<double, double>> gapsPerSecond; ///< (threshold [us], gaps longer than it per second)
    double maxGapUs = 0;
    double stealS = 0; ///< host steal time during the probe, all CPUs [s]
};

/// @brief OpenIGTLink pose → force round trip on loopback, the servo running.
struct IgtlRoundTrip {
    long samples = 0, lost = 0;
    double p50Us = 0, p99Us = 0, maxUs = 0;
};

struct ServoReport {
    std::string machine;
    std::string rtBandwidth;      ///< the kernel's limit on real-time threads (sched_rt_runtime_us)
    int load = 0;                 ///< busy processes beside the loop
    int catchUpPeriods = 0;       ///< the loop's catch-up bound (ServoOptions::catchUpPeriods)
    std::string realtimeNote;     ///< why real-time scheduling was refused, if it was
    std::vector<ServoRun> median; ///< per scene: the median over repeats of achieved rate, jitter p99, overruns
    std::vector<ServoRun> runs;   ///< the long run at 1 kHz, per scene
    std::vector<ServoRun> ladder; ///< per scene and rate
    std::vector<std::pair<std::string, double>> sustainableHz; ///< per scene: the median over its ladders
    std::vector<std::pair<std::string, std::vector<double>>> sustainedPerLadder; ///< per scene, each ladder's
    IgtlRoundTrip igtl;                                                          ///< at 1 kHz on the first scene
    InterruptionFloor floor; ///< measured before the scenes, under the same load
};

ServoReport runServoBench(const ServoBenchOptions& o, const Progress& progress = {});
void printServoReport(std::ostream& os, const ServoReport& r);
nlohmann::json servoReportJson(const ServoReport& r);

} // namespace voxhap::bench
