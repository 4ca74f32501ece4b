// SPDX-License-Identifier: Apache-2.0
/// @file ContactTransient.h
/// @brief Bone-contact vibration, [S19] Eq. 2 (physics.md §2.1, §2.2):
/// F(t) = -A·exp(ln(0.01)·t/d)·sin(2πf·t)·v_in for 0 < t <= d, then 0.
#pragma once

namespace voxhap::haptic {

/// @brief Decaying-sine contact transient scaled by impact speed (Okamura et al. 2001;
/// Kuchenbecker et al. 2006).
struct ContactTransient {
    double amplitudeNsPerM = 150.0; ///< A [N·s/m] (§2.2 [chosen])
    double durationS = 0.040;       ///< d [s]: the envelope falls to 1 % (§2.2 [chosen])
    double frequencyHz = 100.0;     ///< f [Hz] (§2.2 [chosen]: 10 samples per cycle at 1 kHz)
    double peakClampN = 2.0;        ///< |F| cap [N] (§2.2)

    /// @brief Force along the impact direction [N] at @p tS after contact, for impact
    /// speed @p impactMmPerS (positive into the bone); 0 outside (0, d] and for bad input.
    double forceN(double tS, double impactMmPerS) const noexcept;
};

} // namespace voxhap::haptic
