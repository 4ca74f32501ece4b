// SPDX-License-Identifier: Apache-2.0
/// @file InterruptionPhase.cpp
#include "haptic/servo/InterruptionPhase.h"

#include <algorithm>
#include <vector>

namespace voxhap::haptic {

namespace {
std::int64_t mod(std::int64_t a, std::int64_t m) { return ((a % m) + m) % m; }
} // namespace

std::optional<std::int64_t> measureInterruptionPhase(
    const std::function<std::int64_t()>& now, std::int64_t periodNs, const InterruptionPhaseOptions& o)
{
    if (periodNs <= 0 || o.bins < 3 || o.windowNs <= 0) return std::nullopt;
    std::vector<int> hist(std::size_t(o.bins), 0);
    int gaps = 0;
    const std::int64_t start = now(), end = start + o.windowNs;
    for (std::int64_t last = start, t = start; t < end; last = t) {
        t = now();
        if (t - last >= o.minGapNs) {
            ++hist[std::size_t(mod(last, periodNs) * o.bins / periodNs)];
            ++gaps;
        }
    }
    // The busiest bin, counting its two neighbours (the phase may straddle a bin edge;
    // the bins wrap around the period).
    int best = -1, bestCount = 0;
    const auto at = [&](int b) { return hist[std::size_t((b + o.bins) % o.bins)]; };
    for (int b = 0; b < o.bins; ++b) {
        const int c = at(b - 1) + at(b) + at(b + 1);
        if (c > bestCount) best = b, bestCount = c;
    }
    if (best < 0 || bestCount < o.minCount || 4 * bestCount < gaps) return std::nullopt;
    // The earliest of the three bins that holds a gap: the estimate errs early, and a
    // grid placed `lead` before an early estimate still ends its tick before the gap.
    for (const int b : {best - 1, best, best + 1})
        if (at(b) > 0) return mod(std::int64_t(b) * periodNs / o.bins, periodNs);
    return std::nullopt;
}

std::int64_t alignedGridStart(std::int64_t nowNs, std::int64_t periodNs, std::int64_t phaseNs, std::int64_t leadNs)
{
    const std::int64_t want = mod(phaseNs - leadNs, periodNs); // the grid's phase
    return nowNs + mod(want - nowNs, periodNs);
}

} // namespace voxhap::haptic
