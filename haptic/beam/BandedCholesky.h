// SPDX-License-Identifier: Apache-2.0
/// @file BandedCholesky.h
/// @brief Cholesky factorisation and solve of a symmetric positive-definite band
/// matrix, in place, without allocating (physics.md §9.4).
///
/// Hand-written because the beam's matrix is a band of half-width 3 solved every
/// servo tick: Eigen's BandMatrix has no solver and its sparse LDLT allocates on
/// each factorisation. The tests check it against Eigen's dense LLT.
#pragma once

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

/// @brief Factor A = L·Lᵀ in place. @p a holds the lower band of an n×n matrix of
/// half-bandwidth B row by row: a[i·(B+1) + j] = A(i, i − j), j = 0..B.
/// @return false if A is not positive definite (a pivot ≤ 0 or not finite).
template <int B> inline bool choleskyBand(double* a, int n) noexcept
{
    constexpr int W = B + 1;
    for (int i = 0; i < n; ++i) {
        const int k0 = std::max(0, i - B);
        for (int j = k0; j <= i; ++j) {
            double s = a[i * W + (i - j)];
            for (int k = k0; k < j; ++k) s -= a[i * W + (i - k)] * a[j * W + (j - k)];
            if (i == j) {
                if (!(s > 0.0) || !std::isfinite(s)) return false;
                a[i * W] = std::sqrt(s);
            } else {
                a[i * W + (i - j)] = s / a[j * W];
            }
        }
    }
    return true;
}

/// @brief Solve L·Lᵀ·x = b in place (@p x holds b on entry), @p l from choleskyBand.
template <int B> inline void solveBand(const double* l, int n, double* x) noexcept
{
    constexpr int W = B + 1;
    for (int i = 0; i < n; ++i) {
        double s = x[i];
        for (int k = std::max(0, i - B); k < i; ++k) s -= l[i * W + (i - k)] * x[k];
        x[i] = s / l[i * W];
    }
    for (int i = n - 1; i >= 0; --i) {
        double s = x[i];
        for (int k = i + 1; k <= std::min(n - 1, i + B); ++k) s -= l[k * W + (k - i)] * x[k];
        x[i] = s / l[i * W];
    }
}

} // namespace voxhap::haptic
