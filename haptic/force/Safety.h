// SPDX-License-Identifier: Apache-2.0
/// @file Safety.h
/// @brief The last stage of every tick (architecture.md "The force pipeline",
/// step 4; physics.md §6.2–§6.4): a passivity observer and controller, then the
/// device's peak and continuous limits keeping the direction, a rise-rate limit,
/// and a latched fault on anything non-finite.
#pragma once

#include "core/Math.h"
#include "haptic/DeviceLimits.h"

namespace voxhap::haptic {

struct SafetyParams {
    double peakN = 3.3;        ///< device peak force [N]
    double continuousN = 0.88; ///< device continuous force [N]
    /// The I²t budget B = (peak² − continuous²)·this [N²·s]: what holding the peak
    /// would spend in this time [s] [chosen]. The allowed force falls from the peak as
    /// the heat H = ∫(|F|² − continuous²)dt (kept within [0, B]) is spent:
    /// allowed = c + (p − c)·(1 − H/B). A demand held above the peak is therefore
    /// rendered as F(t) = c·(p + c + (p − c)·e^(−t/τ)) / (p + c − (p − c)·e^(−t/τ)),
    /// τ = (p + c)·this/(2c): it starts falling at once and tends to c (physics.md §6.3).
    double peakBudgetS = 1.0;
    double riseNPerS = 2000.0; ///< |F| may grow by at most this per second [N/s] [chosen: 2 N per 1 ms tick]
    double maxDtS = 0.01;      ///< longer ticks count as this [s] [chosen: 10 periods at 1 kHz]
    bool passivity = true;     ///< Hannaford & Ryu (2002) observer and controller (§6.2 guard)

    static SafetyParams fromDevice(const DeviceLimits& d);
};

/// @brief Limits one force stream. Never allocates or throws.
class Safety {
public:
    explicit Safety(const SafetyParams& p = {}) : mP(p) { }

    /// @brief The force to render for the model's @p force with the device at @p devicePoint
    /// [mm] after @p dtS. Non-finite input latches the fault; a faulted stream renders zero.
    /// @p bias is a conservative force added after the passivity observer and before the
    /// limits: Kyung's gravity compensation F_G (physics.md §1.1), whose work the handle's
    /// weight takes back, so the observer must not count it.
    Vec3d apply(const Vec3d& force, const Vec3d& devicePoint, double dtS, const Vec3d& bias = Vec3d::Zero()) noexcept;
    /// @brief Latch the fault from outside (a non-finite device input).
    void latchFault() noexcept { mFault = true, mLast = Vec3d::Zero(); }
    void clearFault() noexcept { mFault = false; }
    bool faulted() const noexcept { return mFault; }
    /// @brief Σ F·Δx delivered to the user so far [N·mm]: positive means energy generated.
    double observedEnergyNmm() const noexcept { return mEnergy; }
    /// @brief How much the peak and I²t limits cut from the last demand [N]: 0 when they
    /// did not act (the rise limit and the passivity controller are not counted).
    double limitedN() const noexcept { return mLimitedN; }
    void reset() noexcept;
    const SafetyParams& params() const noexcept { return mP; }

private:
    SafetyParams mP;
    Vec3d mLast = Vec3d::Zero();
    Vec3d mLastActive = Vec3d::Zero(); ///< mLast without the bias: what the observer counts
    Vec3d mLastPoint = Vec3d::Zero();
    bool mHavePoint = false;
    bool mFault = false;
    double mEnergy = 0.0;
    double mHeat = 0.0;
    double mLimitedN = 0.0;
};

/// @brief @p f scaled to magnitude at most @p limit, keeping its direction.
inline Vec3d clampNorm(const Vec3d& f, double limit) noexcept
{
    const double n = f.norm();
    return n > limit && n > 0.0 ? Vec3d(f * (limit / n)) : f;
}

} // namespace voxhap::haptic
