// SPDX-License-Identifier: Apache-2.0
/// @file InterruptionPhase.h
/// @brief Where, within the servo period, the machine takes the CPU from a spinning
/// real-time thread.
///
/// A kernel without nohz_full keeps its scheduler tick (CONFIG_HZ, 100-1000 Hz) on
/// every busy CPU, a real-time one included, on fixed multiples of the tick period of
/// CLOCK_MONOTONIC. On a virtual machine each tick costs tens of microseconds (on the
/// 2-core CI machine 20-30 µs, 250 times a second). A loop at 50 kHz (a 20 µs period)
/// that the tick interrupts at the moment a tick of its own should run is late by
/// that whole gap and misses its next deadline; the same gap landing just after one
/// of its ticks has finished costs nothing, since the loop was only waiting. When the
/// servo period divides the kernel's tick period the gap always lands at the same
/// phase of the servo grid, so measuring that phase once before the first tick and
/// placing the grid so that a tick ends just before it removes those overruns.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>

namespace voxhap::haptic {

struct InterruptionPhaseOptions {
    std::int64_t windowNs = 60'000'000; ///< spin this long: 15 scheduler ticks at 250 Hz, 6 at 100 Hz [chosen]
    std::int64_t minGapNs = 5'000;      ///< a gap between two clock readings this long is an interruption [chosen]
    int bins = 64;                      ///< phase resolution: the period over this many bins
    /// A phase is reported only when this many gaps began in one bin (or its two
    /// neighbours) and they are at least a quarter of all gaps (a triplet's uniform
    /// share is 3/64): a periodic source, not scattered noise.
    int minCount = 5;
};

/// @brief Spin on @p now for the window and return the phase, in [0, periodNs), at
/// which interruptions begin (the time of the last reading before each gap, modulo
/// the period; the lower edge of the busiest bin, so the estimate errs early), or
/// nothing when the gaps have no dominant phase.
std::optional<std::int64_t> measureInterruptionPhase(
    const std::function<std::int64_t()>& now, std::int64_t periodNs, const InterruptionPhaseOptions& options = {});

/// @brief The first grid origin at or after @p nowNs whose ticks start @p leadNs
/// before the interruption phase @p phaseNs (all modulo @p periodNs).
std::int64_t alignedGridStart(std::int64_t nowNs, std::int64_t periodNs, std::int64_t phaseNs, std::int64_t leadNs);

} // namespace voxhap::haptic
