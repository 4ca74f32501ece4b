// SPDX-License-Identifier: Apache-2.0
/// @file TestServoStep.cpp
/// @brief One servo tick driven by the caller's own loop (ServoStep, issue 22 item 2):
/// the force is the model's while the device answers, and the watchdog of
/// physics.md §6.3 judges the periods from the caller's times: a late callback is a
/// stall, a clock that stands still or runs back is not.

#include "common/Layers.h"
#include "common/Tolerances.h"

#include "haptic/servo/ServoStep.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

// A named namespace: the tests are compiled in unity batches, where another file's
// helpers of the same name would collide.
namespace voxhap::haptic::servo_step_test {
namespace {

constexpr double kBoneMm = 20.0;
constexpr double kTickS = 0.001;     ///< 1 kHz (ServoStepOptions default)
constexpr double kWatchdogS = 0.020; ///< physics.md §6.3 (ServoStepOptions default)
constexpr double kRampS = 0.050;     ///< physics.md §6.3 (ServoStepOptions default)
/// Forces of a few newtons times gains built from a few dozen additions of 0.02 (not
/// a binary fraction): round-off below 1e-13 N; 1e-9 N is far above it and far
/// below the smallest step asserted (0.02 of 4 N).
constexpr double kRoundN = 1e-9;

/// A device that renders whatever is asked (continuous equal to peak: no I²t budget)
/// at 2 N/mm, so that 2 mm into bone is 4 N, reached after two ticks of the 2 N rise
/// limit (physics.md §6.3 item 2).
DeviceLimits stiffDevice()
{
    DeviceLimits dev;
    dev.maxForceN = dev.maxContinuousForceN = 8.5;
    dev.maxStiffnessNPerMm = 2.0;
    return dev;
}
constexpr double kHoldN = 4.0;
constexpr double kHoldDepthMm = kBoneMm + kHoldN / 2.0;

/// Fat without resistance over rigid bone at 20 mm, only the bone contact on: the
/// model demands k·(depth − 20 mm) along −z, the device's stiffness times the
/// penetration (physics.md §1.3).
std::unique_ptr<NeedleForceModel> boneHold()
{
    ForceTerms terms;
    terms.critical = false;
    terms.bone.transient = false;
    return std::make_unique<NeedleForceModel>(ForceModelSetup{.layers = test::fatOverBone(kBoneMm),
        .path = NeedlePath{Vec3d(0, 0, 0), Vec3d(0, 0, 1)},
        .terms = terms,
        .needle = Needle{},
        .device = stiffDevice()});
}

DeviceReading at(double depthMm, double speedMmPerS = 0.0)
{
    DeviceReading r;
    r.tip = Vec3d(0, 0, depthMm);
    r.velocity = Vec3d(0, 0, speedMmPerS);
    r.valid = true;
    return r;
}

// A caller's 1 kHz loop pushing the needle at 10 mm/s from 15 mm into the bone and
// holding it there: every tick renders exactly what a second model, stepped by hand
// with the same readings and the nominal step, computes, events included; held, that
// is the contact force k·(d − 20 mm) = 4 N (physics.md §1.3).
TEST(ServoStep, RendersTheModelForceWhileTheDeviceAnswers)
{
    auto model = boneHold(), twin = boneHold();
    ServoStep servo(*model);
    NeedleOutput expected;
    int contacts = 0;
    for (int k = 0; k < 1000; ++k) {
        const double t = 5.0 + k * kTickS; // the caller's clock need not start at zero
        const double d = std::min(15.0 + 10.0 * k * kTickS, kHoldDepthMm);
        const DeviceReading r = at(d, d < kHoldDepthMm ? 10.0 : 0.0);
        const Vec3d f = servo.step(r, t);
        NeedleInput in;
        in.timeS = t;
        in.dtS = kTickS;
        in.tip = r.tip;
        in.velocity = r.velocity;
        twin->step(in, expected);
        ASSERT_EQ(f, expected.force) << "tick " << k;
        ASSERT_EQ(servo.output().events.size(), expected.events.size()) << "tick " << k;
        for (const Event& e : servo.output().events) contacts += e.type == EventType::BoneContact;
        ASSERT_EQ(servo.gain(), 1.0) << "tick " << k;
    }
    EXPECT_EQ(contacts, 1);
    EXPECT_TRUE(test::nearVec(servo.output().force, Vec3d(0, 0, -kHoldN), kRoundN));
}

/// Hold 2 mm in bone for 100 ticks of 1 ms from t = 0: 4 N at full gain.
void settle(ServoStep& servo, double& t)
{
    for (int k = 0; k < 100; ++k, t += kTickS) servo.step(at(kHoldDepthMm), t);
    ASSERT_EQ(servo.gain(), 1.0);
}

// A callback that comes 30 ms after the previous one (the caller's loop stalled) is
// a period longer than the watchdog's 20 ms: the gain drops by 30/50 at once, to
// 0.4, and climbs back by 1 ms/50 ms = 0.02 per punctual tick (physics.md §6.3).
TEST(ServoStep, ALateCallbackIsAStallOfItsLength)
{
    auto model = boneHold();
    ServoStep servo(*model);
    double t = 0.0;
    settle(servo, t);
    t += 0.030 - kTickS; // the next call comes 30 ms after the last
    const double stalledGain = 1.0 - 0.030 / kRampS;
    Vec3d f = servo.step(at(kHoldDepthMm), t);
    EXPECT_NEAR(servo.gain(), stalledGain, kRoundN);
    EXPECT_TRUE(test::nearVec(f, Vec3d(0, 0, -stalledGain * kHoldN), kRoundN));
    for (int k = 1; k <= 40; ++k) {
        t += kTickS;
        f = servo.step(at(kHoldDepthMm), t);
        const double g = std::min(1.0, stalledGain + k * kTickS / kRampS);
        EXPECT_NEAR(servo.gain(), g, kRoundN) << "tick " << k << " after the stall";
        EXPECT_TRUE(test::nearVec(f, Vec3d(0, 0, -g * kHoldN), kRoundN)) << "tick " << k << " after the stall";
    }
    // A late call shorter than the watchdog is no stall: 19 ms keeps full force.
    t += 0.019;
    servo.step(at(kHoldDepthMm), t);
    EXPECT_EQ(servo.gain(), 1.0);
    static_assert(0.019 < kWatchdogS);
}

// A caller's clock that stands still or runs back (a bad time source) gives no
// period to judge: the tick counts as the nominal 1 ms, and the force stays.
TEST(ServoStep, AClockThatStandsStillOrRunsBackIsNoStall)
{
    auto model = boneHold();
    ServoStep servo(*model);
    double t = 0.0;
    settle(servo, t);
    const double last = t - kTickS; // the time of the last tick
    for (const double back : {0.0, -kTickS, -1.0}) {
        const Vec3d f = servo.step(at(kHoldDepthMm), last + back);
        EXPECT_EQ(servo.gain(), 1.0) << "time step " << back << " s";
        EXPECT_TRUE(test::nearVec(f, Vec3d(0, 0, -kHoldN), kRoundN)) << "time step " << back << " s";
    }
}

// The caller's quiet ticks (no new pose) are 1 ms each of quiet time: the gain is
// held for 20 ms and then falls by 0.02 per tick to zero (physics.md §6.3); a
// release ramps it down at the same rate and ends on the tick that sends zero.
TEST(ServoStep, QuietTicksAndAReleaseRampTheForceToZero)
{
    auto model = boneHold();
    ServoStep servo(*model);
    double t = 0.0;
    settle(servo, t);
    DeviceReading quiet = at(kHoldDepthMm);
    quiet.valid = false;
    const long wait = std::lround(kWatchdogS / kTickS), n = std::lround(kRampS / kTickS);
    for (long q = 1; q <= 80; ++q, t += kTickS) {
        const Vec3d f = servo.step(quiet, t);
        const double g = q <= wait ? 1.0 : std::max(0.0, 1.0 - double(q - wait) / double(n));
        EXPECT_NEAR(servo.gain(), g, kRoundN) << "quiet tick " << q;
        EXPECT_TRUE(test::nearVec(f, Vec3d(0, 0, -g * kHoldN), kRoundN)) << "quiet tick " << q;
        EXPECT_EQ(servo.output().events.size(), 0) << "quiet tick " << q;
    }
    settle(servo, t); // 100 answered ticks bring the gain back to 1 (50 are needed)
    servo.beginRelease();
    Vec3d f{1, 1, 1};
    long k = 0;
    for (; k < 60 && !servo.released(); ++k, t += kTickS) f = servo.step(at(kHoldDepthMm), t);
    EXPECT_TRUE(servo.released());
    EXPECT_GE(k, n); // 50 ms at 1 kHz, one more tick if round-off leaves the 50th a hair above zero
    EXPECT_LE(k, n + 1);
    EXPECT_EQ(f, Vec3d(0, 0, 0)); // exactly zero
}

} // namespace
} // namespace voxhap::haptic::servo_step_test
