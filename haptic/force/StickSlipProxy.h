// SPDX-License-Identifier: Apache-2.0
/// @file StickSlipProxy.h
/// @brief Coulomb-type forces (cutting, C, bone texture) through a 1-D stick-slip
/// proxy along the needle axis (physics.md §6.2): the proxy holds still while the
/// coupling spring k_c·(d − p) is below the friction threshold and slips so that
/// it never exceeds it. Unlike a linear zone F/ε, its stiffness is k_c, which is
/// kept within the device's stable stiffness, and it dissipates on every slip.
#pragma once

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

class StickSlipProxy {
public:
    explicit StickSlipProxy(double couplingNPerMm = 0.5) : mK(couplingNPerMm > 0.0 ? couplingNPerMm : 0.5) { }

    /// @brief Move the needle to depth @p d [mm] against threshold @p thresholdN [N];
    /// returns the resistance along the insertion axis [N] (positive pushes the needle out).
    double update(double d, double thresholdN) noexcept
    {
        if (!std::isfinite(d)) return 0.0;
        const double t = std::isfinite(thresholdN) ? std::max(0.0, thresholdN) : 0.0;
        if (!mEngaged) mProxy = d, mEngaged = true;
        double f = mK * (d - mProxy);
        if (f > t)
            mProxy = d - t / mK, f = t; // slip forward
        else if (f < -t)
            mProxy = d + t / mK, f = -t; // slip backward
        return f;
    }
    /// @brief Start sliding forward at @p thresholdN: at a pop the tissue gives way and
    /// the needle is already moving, so kinetic friction applies at once (no stick phase).
    void preload(double d, double thresholdN) noexcept
    {
        if (!std::isfinite(d) || !std::isfinite(thresholdN)) return;
        mProxy = d - std::max(0.0, thresholdN) / mK;
        mEngaged = true;
    }
    void reset() noexcept { mEngaged = false; }
    double proxy() const noexcept { return mProxy; }
    double coupling() const noexcept { return mK; }

private:
    double mK;
    double mProxy = 0.0;
    bool mEngaged = false;
};

} // namespace voxhap::haptic
