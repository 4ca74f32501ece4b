// SPDX-License-Identifier: Apache-2.0
/// @file ProcessFigures.h
/// @brief What a benchmark reports of its own process beside its timings
/// (docs/benchmarks.md: this machine is shared): peak and current resident
/// memory, CPU time, and the load average that says how much of the cores
/// other processes took.
#pragma once

#include <sys/resource.h>

#include <fstream>
#include <string>

namespace voxhap::bench {

/// @brief The process's peak resident memory so far [MiB] (ru_maxrss).
inline double peakRssMb()
{
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_maxrss) / 1024.0;
}

/// @brief The process's resident memory now [MiB] (VmRSS), as against the peak.
inline double rssMb()
{
    std::ifstream in("/proc/self/status");
    std::string key;
    double kb = 0;
    while (in >> key) {
        if (key == "VmRSS:") {
            in >> kb;
            break;
        }
        std::getline(in, key);
    }
    return kb / 1024.0;
}

/// @brief User and system CPU time of the process so far [s].
inline double cpuSeconds()
{
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// @brief The 1-minute load average: other processes' demand for the same cores.
inline double loadAverage()
{
    std::ifstream in("/proc/loadavg");
    double l = -1;
    in >> l;
    return l;
}

} // namespace voxhap::bench
