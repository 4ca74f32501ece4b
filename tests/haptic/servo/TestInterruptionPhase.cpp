// SPDX-License-Identifier: Apache-2.0
/// @file TestInterruptionPhase.cpp
/// @brief The phase of periodic interruptions, found from clock readings alone, and
/// the grid placed before it (haptic/servo/InterruptionPhase.h).
#include "haptic/servo/InterruptionPhase.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>

namespace voxhap::haptic {
namespace {

/// A clock read by a spinning thread: each reading 100 ns after the last, except that
/// a reading past an interruption's start comes @c gapNs later. Periodic interruptions
/// begin at tickOffsetNs + k·tickPeriodNs (a kernel's scheduler tick); @c noise more
/// begin at random times.
struct SpinClock {
    std::int64_t t = 3'000'000'000;
    std::int64_t tickPeriodNs = 4'000'000, tickOffsetNs = 1'234'500, gapNs = 25'000;
    std::int64_t nextTick = 0;
    std::mt19937_64 rng{7};
    double noisePerReading = 0.0; ///< chance that a reading meets a random interruption
    std::int64_t operator()()
    {
        if (nextTick == 0) nextTick = (t / tickPeriodNs + 1) * tickPeriodNs + tickOffsetNs;
        t += 100;
        if (t >= nextTick) {
            t += gapNs;
            nextTick += tickPeriodNs;
        } else if (noisePerReading > 0.0 && std::uniform_real_distribution<double>(0, 1)(rng) < noisePerReading) {
            t += 8'000;
        }
        return t;
    }
};

constexpr std::int64_t kPeriodNs = 20'000; // 50 kHz
constexpr int kBins = 64;                  // InterruptionPhaseOptions default
// The tick's phase within the 20 µs period: 1 234 500 ns mod 20 000 = 14 500 ns. The
// reading before the gap is up to one 100 ns step earlier; the estimate is the lower
// edge of the earliest of three bins, so it may err early by up to two bin widths plus
// that step, never late.
constexpr std::int64_t kTruePhaseNs = 14'500;
constexpr std::int64_t kEarlyAllowanceNs = 2 * kPeriodNs / kBins + 100;

TEST(InterruptionPhase, PeriodicGapsAreFoundAtTheirPhaseErringEarlyNeverLate)
{
    SpinClock clock;
    const auto phase = measureInterruptionPhase(std::ref(clock), kPeriodNs);
    ASSERT_TRUE(phase.has_value());
    EXPECT_LE(*phase, kTruePhaseNs);
    EXPECT_GE(*phase, kTruePhaseNs - kEarlyAllowanceNs);
}

// Random 8 µs interruptions beside the periodic ones (about 24 in the 60 ms window, at
// uniformly spread phases, against the 15 scheduler ticks): the periodic phase still wins.
TEST(InterruptionPhase, PeriodicPhaseWinsOverScatteredGaps)
{
    SpinClock clock;
    clock.noisePerReading = 4e-5;
    const auto phase = measureInterruptionPhase(std::ref(clock), kPeriodNs);
    ASSERT_TRUE(phase.has_value());
    EXPECT_LE(*phase, kTruePhaseNs);
    EXPECT_GE(*phase, kTruePhaseNs - kEarlyAllowanceNs);
}

// Only scattered gaps: no phase is claimed, and the loop keeps its unaligned grid.
TEST(InterruptionPhase, ScatteredGapsAloneGiveNoPhase)
{
    SpinClock clock;
    clock.tickPeriodNs = 1'000'000'000'000; // no periodic interruption within the window
    clock.noisePerReading = 4e-5;
    EXPECT_FALSE(measureInterruptionPhase(std::ref(clock), kPeriodNs).has_value());
    SpinClock quiet;
    quiet.tickPeriodNs = 1'000'000'000'000;
    EXPECT_FALSE(measureInterruptionPhase(std::ref(quiet), kPeriodNs).has_value());
}

// The grid origin: not before now, less than a period after it, and its ticks start
// `lead` before the phase (modulo the period), for phases on both sides of the lead.
TEST(InterruptionPhase, AlignedGridStartsLeadBeforeThePhase)
{
    const std::int64_t lead = 3'000;
    for (const std::int64_t now : {std::int64_t(7'000'000'123), std::int64_t(7'000'019'999)}) {
        for (const std::int64_t phase : {std::int64_t(0), std::int64_t(1'000), std::int64_t(14'500)}) {
            const std::int64_t start = alignedGridStart(now, kPeriodNs, phase, lead);
            EXPECT_GE(start, now);
            EXPECT_LT(start, now + kPeriodNs);
            EXPECT_EQ(((start + lead - phase) % kPeriodNs + kPeriodNs) % kPeriodNs, 0) << now << " " << phase;
        }
    }
}

} // namespace
} // namespace voxhap::haptic
