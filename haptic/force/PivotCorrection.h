// SPDX-License-Identifier: Apache-2.0
/// @file PivotCorrection.h
/// @brief Lateral correction about the skin pivot from layered Kelvin (standard
/// linear solid) elements, [K01] Eq. 2–3 as reconstructed in physics.md §1.4.
#pragma once

#include <array>

namespace voxhap::haptic {

/// @brief One layer's standard linear solid: spring k1 parallel to (k2 in series with b),
/// discretised by backward Euler (unconditionally stable):
/// F[n] = (τ·F[n-1] + T·k1·x[n] + b·(1 + k1/k2)·(x[n] - x[n-1])) / (τ + T),  τ = b/k2.
class KelvinElement {
public:
    KelvinElement() = default;
    /// @param k1NPerMm relaxed stiffness, @param k2NPerMm series spring, @param tauS relaxation time b/k2
    KelvinElement(double k1NPerMm, double k2NPerMm, double tauS) : mK1(k1NPerMm), mK2(k2NPerMm), mTau(tauS) { }
    /// @brief Advance by @p periodS with deflection @p xMm; returns the force [N].
    /// A period of 0 (or negative, or NaN) is treated as the smallest positive step: never divides by 0.
    double step(double xMm, double periodS) noexcept;
    double force() const noexcept { return mF; }
    void reset() noexcept { mF = 0.0, mXPrev = 0.0; }

private:
    double mK1 = 0, mK2 = 0, mTau = 0;
    double mF = 0, mXPrev = 0;
};

/// @brief Parameters of the pivot correction (physics.md §1.4 defaults [chosen]).
struct PivotParams {
    double kappa1NPerMm2 = 4.77e-3; ///< κ1: per-depth stiffness so F_C = 2 N at 10°, D = 60 mm, L_h = 30 mm
    double kappa2NPerMm2 = 4.77e-3; ///< κ2 = κ1
    double tauS = 0.020;            ///< τ = 20 ms
    double hubDistanceMm = 30.0;    ///< L_h: pivot to hub
    double layerThicknessMm = 1.0;  ///< h: depth of each Kelvin layer
    double maxForceN = 2.0;         ///< [K01] |F_C| <= 2 N
};

/// @brief F_C = (1/L_h)·Σ F_i·r_i with x_i = r_i·θ, clamped to maxForceN (physics.md §1.4).
/// @note Fixed capacity (kMaxLayers): never allocates.
class PivotCorrection {
public:
    static constexpr int kMaxLayers = 256;
    explicit PivotCorrection(const PivotParams& p = {});
    /// @brief Advance with tilt @p thetaRad from the initial line and inserted depth @p depthMm
    /// below the pivot; returns the correction force toward the line [N], signed as θ
    /// (the caller applies it perpendicular to the needle, back toward the initial line).
    double update(double thetaRad, double depthMm, double periodS) noexcept;
    void reset() noexcept;
    const PivotParams& params() const { return mP; }

private:
    PivotParams mP;
    std::array<KelvinElement, kMaxLayers> mLayers;
    int mTouched = 0; ///< layers ever reached: deeper ones hold zero state and are skipped
};

} // namespace voxhap::haptic
