// SPDX-License-Identifier: Apache-2.0
/// @file SimulatedDevice.cpp
#include "SimulatedDevice.h"

#include <cmath>
#include <cstdint>
#include <ctime>

namespace simdev {

namespace {

std::int64_t nowNs() noexcept
{
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return std::int64_t(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

void sleepUntilNs(std::int64_t ns) noexcept
{
    const timespec ts{time_t(ns / 1000000000), long(ns % 1000000000)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
}

} // namespace

SimulatedDevice::SimulatedDevice(const Hand& hand, double rateHz) : mHand(hand), mPeriodS(1.0 / rateHz) { }

SimulatedDevice::~SimulatedDevice() { stop(); }

void SimulatedDevice::start(ServoCallback callback, void* user)
{
    mStop.store(false);
    mThread = std::thread([this, callback, user] { run(callback, user); });
}

void SimulatedDevice::stop()
{
    mStop.store(true);
    if (mThread.joinable()) mThread.join();
}

void SimulatedDevice::run(ServoCallback callback, void* user) noexcept
{
    const Hand& h = mHand;
    const double dt = mPeriodS;
    double x = h.startMm, v = 0.0; // the tip along the line [mm], [mm/s]
    const std::int64_t periodNs = std::int64_t(std::llround(dt * 1e9));
    std::int64_t deadline = nowNs();
    for (long n = 0; !mStop.load(std::memory_order_relaxed); ++n) {
        HandleState s;
        s.timeS = double(n) * dt;
        for (int i = 0; i < 3; ++i) {
            s.position[i] = h.origin[i] + x * h.direction[i];
            s.velocity[i] = v * h.direction[i];
            s.direction[i] = h.direction[i];
        }
        double f[3] = {0, 0, 0};
        callback(s, f, user);
        // The hand: grip spring and damper to the set point, plus the rendered force
        // along the line; semi-implicit Euler over one period. N/kg = m/s² = 1000 mm/s².
        const double setMm = h.startMm + h.speedMmPerS * s.timeS;
        const double along = f[0] * h.direction[0] + f[1] * h.direction[1] + f[2] * h.direction[2];
        const double forceN = h.gripNPerMm * (setMm - x) + h.dampingNsPerMm * (h.speedMmPerS - v) + along;
        v += forceN / h.massKg * 1000.0 * dt;
        x += v * dt;
        mTicks.fetch_add(1, std::memory_order_relaxed);
        // Absolute deadlines: the rate does not drift with the time each period takes.
        deadline += periodNs;
        if (nowNs() > deadline) mLate.fetch_add(1, std::memory_order_relaxed);
        sleepUntilNs(deadline);
    }
}

} // namespace simdev
