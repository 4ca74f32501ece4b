// SPDX-License-Identifier: Apache-2.0
/// @file TestSafety.cpp
/// @brief The safety stage on its own (issue 25 item 1; physics.md §6.3): the rise
/// limit under a step demand, and the I²t budget under a force held above the
/// continuous limit, against closed forms written here. The same limits through the
/// servo loop, with the built-in scenes' devices, are in servo/TestServo.cpp.

#include "common/Tolerances.h"

#include "haptic/force/Safety.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

// A named namespace: the tests are compiled in unity batches, where another file's
// helpers of the same name would collide.
namespace voxhap::haptic::safety_test {
namespace {

// The documented constants (physics.md §6.3), written here rather than read from
// SafetyParams so that a change of the code shows as a failure.
constexpr double kRiseNPerS = 2000.0; ///< §6.3 item 2: 2 N per 1 ms tick
constexpr double kMaxDtS = 0.010;     ///< §6.3 item 3: ticks longer than 10 ms count as 10 ms
constexpr double kBudgetS = 1.0;      ///< §6.3 item 1: budget (peak² − continuous²)·1 s
constexpr double kTickS = 0.001;      ///< the servo period at 1 kHz

/// Forces here are sums and products of a few doubles of order 1–60 N: round-off is
/// a few ulps of 60 N (~1e-14 N). 1e-9 N is far above it and far below any effect
/// tested (the smallest, one step of the I²t limit, is ~1e-3 N).
constexpr double kRoundN = 1e-9;

/// A rise limit far beyond any force here (10⁶ N per tick), to look at the I²t budget alone.
constexpr double kNoRiseLimitNPerS = 1e9;

/// The hand holds still: the passivity observer sees no motion (Δx = 0) and stays out.
const Vec3d kPoint(1.0, 2.0, 3.0);

/// A demand direction that is not an axis: the clamps must keep it (§6.3 "direction kept").
Vec3d demandDirection() { return Vec3d(2.0, -3.0, 6.0) / 7.0; }

SafetyParams limits(double peakN, double continuousN, double riseNPerS = kRiseNPerS)
{
    SafetyParams p;
    p.peakN = peakN;
    p.continuousN = continuousN;
    p.riseNPerS = riseNPerS;
    return p;
}

/// The rendered force has the demand's direction and magnitude @p n.
testing::AssertionResult renders(const Vec3d& f, double n) { return test::nearVec(f, n * demandDirection(), kRoundN); }

// §6.3 item 2: a step demand rises by exactly riseNPerS·dt per tick until it is met;
// below the continuous force the I²t budget never enters (|F|² − c² ≤ 0 leaves the
// heat at zero), so |F_k| = min((k + 1)·2 N, D) on tick k, in the demand's direction.
TEST(Safety, StepDemandRisesByTheRateLimitPerTick)
{
    Safety s(limits(31.0, 10.0)); // the senac scenes' virtuose-6d
    const double demandN = 9.0;   // below the continuous 10 N
    for (int k = 0; k < 8; ++k) {
        const Vec3d f = s.apply(demandN * demandDirection(), kPoint, kTickS);
        EXPECT_TRUE(renders(f, std::min((k + 1) * kRiseNPerS * kTickS, demandN))) << "tick " << k;
    }
    // A drop is immediate: a pop or a critical structure reaches the hand at once.
    EXPECT_TRUE(renders(s.apply(1.0 * demandDirection(), kPoint, kTickS), 1.0));
    EXPECT_TRUE(renders(s.apply(Vec3d::Zero(), kPoint, kTickS), 0.0));
    // ... and the next rise starts from there.
    EXPECT_TRUE(renders(s.apply(demandN * demandDirection(), kPoint, kTickS), kRiseNPerS * kTickS));
}

// The rise per tick is riseNPerS times the tick's length: 1 N for 0.5 ms, 20 N for any
// tick of 10 ms or more (§6.3 item 3 clamps dt), nothing for a zero or non-finite dt.
TEST(Safety, RisePerTickFollowsTheClampedTickLength)
{
    // Continuous equal to peak: no I²t budget, only the peak and the rise limit.
    const double peakN = 50.0;
    struct Case {
        double dtS, risePerTickN;
    };
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (const Case c : {Case{0.0005, kRiseNPerS * 0.0005}, Case{0.05, kRiseNPerS * kMaxDtS},
             Case{1.0, kRiseNPerS * kMaxDtS}, Case{0.0, 0.0}, Case{-0.001, 0.0}, Case{nan, 0.0}}) {
        Safety s(limits(peakN, peakN));
        for (int k = 0; k < 4; ++k) {
            const Vec3d f = s.apply(45.0 * demandDirection(), kPoint, c.dtS);
            EXPECT_TRUE(renders(f, std::min((k + 1) * c.risePerTickN, 45.0))) << "dt " << c.dtS << " tick " << k;
        }
        EXPECT_FALSE(s.faulted()); // a bad dt is not a fault: the force is finite
    }
}

/// The closed form of §6.3 item 1 for a demand held above the peak p with continuous
/// force c and budget B = (p² − c²)·T_b. With s = (allowed − c)/(p − c) = 1 − H/B and
/// dH/dt = F² − c² = (p − c)·s·(2c + (p − c)·s) while F = allowed:
///   ds/dt = −(p − c)·s·(2c + (p − c)·s)/B,
/// separable: ln(s/(2c + (p − c)·s)) = −t/τ + ln(1/(p + c)), τ = B/(2c·(p − c)) = (p + c)·T_b/(2c),
/// so F(t) = c + (p − c)·s(t) = c·(p + c + (p − c)·e^(−t/τ)) / (p + c − (p − c)·e^(−t/τ)).
/// F(0) = p, F(∞) = c, and ∫(F² − c²)dt over [0, ∞) = B.
double heldAbovePeakN(double p, double c, double tS)
{
    const double tau = (p + c) * kBudgetS / (2.0 * c);
    const double e = std::exp(-tS / tau);
    return c * (p + c + (p - c) * e) / (p + c - (p - c) * e);
}

/// How far below F(t) the rendered force may be after @p ticks: the safety stage
/// updates the heat once per tick, the forward Euler step s ← s − h(s)·dt of the ODE
/// above, h(s) = (p − c)·s·(2c + (p − c)·s)/B. s(t) is convex (s'' = h'·h ≥ 0), so each
/// step lands below the curve by at most s''·dt²/2, and as h' ≥ 0 the Euler map does
/// not amplify an earlier gap: after k ticks 0 ≤ s(k·dt) − s_k ≤ k·dt²·max s''/2, with
/// max s'' = h'(1)·h(1) = 2p/((p + c)·T_b²). In force, times (p − c).
double eulerGapN(double p, double c, long ticks)
{
    return (p - c) * double(ticks) * kTickS * kTickS * p / ((p + c) * kBudgetS * kBudgetS);
}

struct DeviceCase {
    const char* name;
    double peakN, continuousN;
};

/// Touch and PHANToM Premium presets (DeviceLimits.cpp, physics.md §6.3, §1.1) and
/// the scenes' own devices (data/scenes/*.json).
const std::vector<DeviceCase>& devices()
{
    static const std::vector<DeviceCase> d = {
        {"touch", 3.3, 0.88},
        {"phantom-premium", 8.5, 1.4},
        {"virtuose-6d", 31.0, 10.0},
        {"bench-rig", 20.0, 15.0},
        {"lp-belt", 20.0, 17.0},
    };
    return d;
}

// §6.3 item 1: a demand of twice the peak held for 10 s follows the closed form F(t)
// from the peak down to the continuous force, tick by tick, never above it and at
// most the Euler gap below; the heat ∫(F² − c²)dt never exceeds the budget.
TEST(Safety, HeldDemandDecaysAlongTheI2tClosedForm)
{
    for (const DeviceCase& d : devices()) {
        SCOPED_TRACE(d.name);
        const double p = d.peakN, c = d.continuousN;
        const double budget = (p * p - c * c) * kBudgetS;
        Safety s(limits(p, c, kNoRiseLimitNPerS));
        double heat = 0.0;
        const long ticks = 10000;
        for (long k = 0; k < ticks; ++k) {
            const Vec3d f = s.apply(2.0 * p * demandDirection(), kPoint, kTickS);
            const double n = f.norm();
            const double closed = heldAbovePeakN(p, c, double(k) * kTickS);
            ASSERT_LE(n, closed + kRoundN) << "tick " << k;
            ASSERT_GE(n, closed - eulerGapN(p, c, k) - kRoundN) << "tick " << k;
            ASSERT_TRUE(renders(f, n)) << "tick " << k;
            heat += (n * n - c * c) * kTickS;
            ASSERT_LE(heat, budget + kRoundN) << "tick " << k;
        }
        // 10 s is 2.8 to 9 time constants here: the force has come down to the continuous
        // force within F(10 s) − c of it.
        EXPECT_LE(
            s.apply(2.0 * p * demandDirection(), kPoint, kTickS).norm() - c, heldAbovePeakN(p, c, 10.0) - c + kRoundN);
    }
}

// §6.3 item 1: a demand D between the continuous force and the peak is rendered in
// full while the limit allows it. Held at D, the heat before tick k is k·(D² − c²)·dt,
// so allowed ≥ D while k ≤ K = B·(p − D) / ((p − c)·(D² − c²)·dt); the tick after
// ⌊K⌋ renders allowed = c + (p − c)·(1 − (⌊K⌋ + 1)·(D² − c²)·dt/B) < D.
TEST(Safety, DemandBetweenContinuousAndPeakIsRenderedUntilTheBudgetReachesIt)
{
    struct Case {
        double p, c, demandN;
    };
    // K = 1503.33 and 1684.65 ticks: far from an integer at the round-off of kRoundN.
    for (const Case t : {Case{31.0, 10.0, 20.0}, Case{3.3, 0.88, 2.0}}) {
        SCOPED_TRACE(t.demandN);
        const double b = (t.p * t.p - t.c * t.c) * kBudgetS;
        const double rate = t.demandN * t.demandN - t.c * t.c;
        const long last = long(std::floor(b * (t.p - t.demandN) / ((t.p - t.c) * rate * kTickS)));
        Safety s(limits(t.p, t.c, kNoRiseLimitNPerS));
        for (long k = 0; k <= last; ++k) {
            ASSERT_TRUE(renders(s.apply(t.demandN * demandDirection(), kPoint, kTickS), t.demandN)) << "tick " << k;
        }
        const double allowed = t.c + (t.p - t.c) * (1.0 - double(last + 1) * rate * kTickS / b);
        EXPECT_LT(allowed, t.demandN);
        EXPECT_TRUE(renders(s.apply(t.demandN * demandDirection(), kPoint, kTickS), allowed));
    }
}

// §6.3 item 1: the heat is spent at F² − c² and comes back at c² − F² (kept ≥ 0). Hold
// twice the peak for 1 s (heat H = Σ(F² − c²)·dt of the forces rendered), release to
// zero for R ticks (heat max(0, H − R·c²·dt)), then demand again: the first tick
// renders c + (p − c)·(1 − heat/B). After 1 s at the limit H ≈ B·(1 − s(1 s)) = 485 N²·s
// (s(1 s) = (F(1 s) − c)/(p − c) = 0.437 from the closed form above), H/c² ≈ 4.85 s:
// a release of 6 s gives back the whole peak.
TEST(Safety, BudgetRecoversAtTheContinuousForceSquared)
{
    const double p = 31.0, c = 10.0, b = (p * p - c * c) * kBudgetS;
    for (const long release : {0L, 500L, 2000L, 6000L}) {
        SCOPED_TRACE(release);
        Safety s(limits(p, c, kNoRiseLimitNPerS));
        double heat = 0.0;
        for (int k = 0; k < 1000; ++k) {
            const double n = s.apply(2.0 * p * demandDirection(), kPoint, kTickS).norm();
            heat += (n * n - c * c) * kTickS;
        }
        for (long k = 0; k < release; ++k) ASSERT_TRUE(renders(s.apply(Vec3d::Zero(), kPoint, kTickS), 0.0));
        heat = std::max(0.0, heat - double(release) * c * c * kTickS);
        const double expected = c + (p - c) * (1.0 - heat / b);
        EXPECT_TRUE(renders(s.apply(2.0 * p * demandDirection(), kPoint, kTickS), expected));
        if (release == 6000) {
            EXPECT_NEAR(expected, p, kRoundN);
        }
    }
}

} // namespace
} // namespace voxhap::haptic::safety_test
