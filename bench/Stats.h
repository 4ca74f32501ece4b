// SPDX-License-Identifier: Apache-2.0
/// @file Stats.h
/// @brief Summary of repeated measurements, as benchmarks.md reports them:
/// mean with its sample standard deviation, and the median.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace voxhap::bench {

struct SampleStats {
    double mean = 0, sd = 0, median = 0;
    int n = 0;
};

/// @brief Mean, sample standard deviation (n − 1) and median of @p x.
inline SampleStats sampleStats(std::vector<double> x)
{
    SampleStats s;
    s.n = int(x.size());
    if (x.empty()) return s;
    for (double v : x) s.mean += v / double(x.size());
    for (double v : x) s.sd += (v - s.mean) * (v - s.mean) / double(std::max<std::size_t>(1, x.size() - 1));
    s.sd = std::sqrt(s.sd);
    std::sort(x.begin(), x.end());
    s.median = x.size() % 2 ? x[x.size() / 2] : 0.5 * (x[x.size() / 2 - 1] + x[x.size() / 2]);
    return s;
}

} // namespace voxhap::bench
