// SPDX-License-Identifier: Apache-2.0
/// @file WinklerBeam.h
/// @brief An Euler–Bernoulli beam on a Winkler foundation, deflecting in two
/// lateral directions (physics.md §9.2, §9.4).
///
/// EI·w'''' + k(x)·(w − r(x)) = 0 on [0, L] with a lateral force at x = L, w the
/// deflection, r the foundation's rest position and k its modulus [N/mm²]. Cubic
/// Hermite elements (w and its slope at each node), so a cantilever's nodal
/// deflections under end loads are exact; the foundation is integrated by
/// four-point Gauss quadrature over the part of each element it covers. Both
/// directions share one matrix: one band factorisation, two right-hand sides.
/// All buffers are sized at construction: a load case and its solve never
/// allocate.
#pragma once

#include "haptic/beam/BandedCholesky.h"

#include <array>
#include <vector>

namespace voxhap::haptic {

class WinklerBeam {
public:
    static constexpr int kBand = 3; ///< half-bandwidth: a node's two unknowns couple to the next node's

    /// @param clampedStart the end x = 0 is clamped (w = w' = 0); else free
    /// @throw ValueError on fewer than one element, or a length or EI that is not positive and finite
    WinklerBeam(int elements, double lengthMm, double eiNmm2, bool clampedStart);

    int elements() const { return mElements; }
    double elementLengthMm() const { return mH; }
    double lengthMm() const { return mH * mElements; }
    double bendingStiffnessNmm2() const { return mEi; }

    /// @brief Start a load case: the beam's bending stiffness, no foundation, no load.
    void begin() noexcept;
    /// @brief Add the foundation over [@p fromMm, L]: @p sample(x, k, r1, r2) gives
    /// the modulus k [N/mm²] and the rest position (r1, r2) [mm] at x.
    template <typename Sample> void addFoundation(double fromMm, Sample&& sample) noexcept;
    /// @brief Add a lateral force (f1, f2) [N] at the end x = L.
    void addEndForce(double f1, double f2) noexcept;
    /// @brief Hold the end x = L at the lateral position (w1, w2) [mm], its slope free
    /// (a pin: bone holding the tip, physics.md §9.5). After the foundation and the
    /// loads of this load case, before solve(); exact (the unknown is eliminated).
    void pinEnd(double w1, double w2) noexcept;
    /// @brief Factor and solve. @return false (deflections zero) if the matrix is
    /// not positive definite, as a free beam without foundation, or not finite.
    bool solve() noexcept;

    /// @brief Deflection [mm] of node @p i (0..elements) in direction @p c (0, 1).
    double deflection(int i, int c) const noexcept { return mU[std::size_t(c)][std::size_t(2 * i)]; }
    /// @brief Slope dw/dx of node @p i in direction @p c.
    double slope(int i, int c) const noexcept { return mU[std::size_t(c)][std::size_t(2 * i + 1)]; }
    /// @brief Deflection at @p x [mm] (the elements' cubic), both directions.
    void deflectionAt(double x, double& w1, double& w2) const noexcept;
    /// @brief What the clamp at x = 0 applies to the beam: the lateral force [N]
    /// and the moment [N·mm] in each direction's plane (zero for a free start).
    void startReaction(double& f1, double& f2, double& m1, double& m2) const noexcept;
    /// @brief After a successful solve(): the force [N/mm] per unit lateral
    /// translation of the clamped start, its slope held (the Schur complement of
    /// the free unknowns; one more band solve on the factor). The same in both
    /// directions; 0 for a free start. Never allocates.
    double startTranslationStiffness() noexcept;

private:
    using Local = std::array<std::array<double, 4>, 4>;
    /// Hermite shape functions at local t ∈ [0, 1] of an element of length h.
    static std::array<double, 4> shape(double t, double h) noexcept;
    void scatter(int e, const Local& k, const std::array<double, 4>& f1, const std::array<double, 4>& f2) noexcept;

    int mElements;
    double mH, mEi;
    bool mClamped;
    int mOffset; ///< unknowns eliminated at the start: 2 when clamped
    int mUnknowns;
    Local mElement{};                            ///< the bending stiffness of one element
    std::vector<double> mBase, mBand;            ///< lower band, (kBand + 1) per row
    std::array<std::vector<double>, 2> mRhs, mU; ///< per direction; mU over every node's (w, w')
    std::vector<double> mScratch;                ///< a third right-hand side (startTranslationStiffness)
    bool mFactored = false;                      ///< mBand holds this load case's factor
    bool mPinned = false;                        ///< this load case holds the end (pinEnd)
    Local mStartFoundation{};                    ///< element 0's foundation, for the clamp's reaction
    std::array<std::array<double, 4>, 2> mStartLoad{};
};

template <typename Sample> void WinklerBeam::addFoundation(double fromMm, Sample&& sample) noexcept
{
    // Four-point Gauss–Legendre: exact for the degree-6 products of two cubics
    // under a constant k and a cubic rest position.
    static constexpr double kNode[4] = {
        -0.86113631159405257522, -0.33998104358485626480, 0.33998104358485626480, 0.86113631159405257522};
    static constexpr double kWeight[4] = {
        0.34785484513745385737, 0.65214515486254614263, 0.65214515486254614263, 0.34785484513745385737};
    if (!(fromMm < lengthMm())) return;
    const int first = fromMm <= 0.0 ? 0 : std::min(mElements - 1, int(fromMm / mH));
    for (int e = first; e < mElements; ++e) {
        const double x0 = e * mH;
        const double a = std::max(0.0, fromMm - x0); // the covered part [a, h] of the element
        if (!(a < mH)) continue;
        Local k{};
        std::array<double, 4> f1{}, f2{};
        bool any = false;
        for (int g = 0; g < 4; ++g) {
            const double xl = a + 0.5 * (mH - a) * (1.0 + kNode[g]);
            const double weight = 0.5 * (mH - a) * kWeight[g];
            double kx = 0.0, r1 = 0.0, r2 = 0.0;
            sample(x0 + xl, kx, r1, r2);
            if (!(kx > 0.0)) continue;
            any = true;
            const std::array<double, 4> n = shape(xl / mH, mH);
            for (int i = 0; i < 4; ++i) {
                const double wi = weight * kx * n[std::size_t(i)];
                f1[std::size_t(i)] += wi * r1;
                f2[std::size_t(i)] += wi * r2;
                for (int j = 0; j <= i; ++j) k[std::size_t(i)][std::size_t(j)] += wi * n[std::size_t(j)];
            }
        }
        if (any) scatter(e, k, f1, f2);
    }
}

} // namespace voxhap::haptic
