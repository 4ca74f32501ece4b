// SPDX-License-Identifier: Apache-2.0
/// @file LorChannel.h
/// @brief The loss-of-resistance syringe: a plunger force channel (physics.md §2.3).
/// The plunger is blocked while the bevel sits in ligament and frees up when it
/// enters the epidural space; the drop follows the patient's LOR time constant
/// (quick 50, average 150, slow 400 ms [chosen]). A rise is immediate: the
/// plunger stalls as soon as the bevel is occluded.
#pragma once

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

struct LorParams {
    double blockedForceN = 10.0;  ///< plunger force with the bevel occluded [N] [chosen]
    double timeConstantS = 0.150; ///< drop time constant [s] (§2.3 average)
};

class LorChannel {
public:
    explicit LorChannel(const LorParams& p = {}) : mP(p) { }
    /// @brief Advance by @p dtS with the tip in a layer of resistance @p r (0..1); returns the plunger force [N].
    double update(double r, double dtS) noexcept
    {
        const double target = mP.blockedForceN * std::clamp(std::isfinite(r) ? r : 1.0, 0.0, 1.0);
        if (target >= mForce || !(mP.timeConstantS > 0.0)) {
            mForce = target;
        } else if (dtS > 0.0 && std::isfinite(dtS)) {
            mForce = target + (mForce - target) * std::exp(-dtS / mP.timeConstantS); // exact first-order decay
        }
        return mForce;
    }
    void reset() noexcept { mForce = 0.0; }
    double force() const noexcept { return mForce; }
    const LorParams& params() const noexcept { return mP; }

private:
    LorParams mP;
    double mForce = 0.0;
};

} // namespace voxhap::haptic
