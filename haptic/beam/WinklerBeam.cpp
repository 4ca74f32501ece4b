// SPDX-License-Identifier: Apache-2.0
/// @file WinklerBeam.cpp
/// @brief Assembly, the band solve and the clamp's reaction of WinklerBeam.

#include "haptic/beam/WinklerBeam.h"

#include "core/Errors.h"

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

WinklerBeam::WinklerBeam(int elements, double lengthMm, double eiNmm2, bool clampedStart)
    : mElements(elements), mH(lengthMm / std::max(1, elements)), mEi(eiNmm2), mClamped(clampedStart),
      mOffset(clampedStart ? 2 : 0), mUnknowns(2 * (elements + 1) - (clampedStart ? 2 : 0))
{
    if (elements < 1) throw ValueError("beam: at least one element");
    if (!(lengthMm > 0.0) || !std::isfinite(lengthMm)) throw ValueError("beam: the length must be positive");
    if (!(eiNmm2 > 0.0) || !std::isfinite(eiNmm2)) throw ValueError("beam: EI must be positive");
    // The Hermite element's bending stiffness, EI/h³ times the classical matrix.
    const double h = mH, c = mEi / (h * h * h);
    mElement = {{{12 * c, 6 * h * c, -12 * c, 6 * h * c}, {6 * h * c, 4 * h * h * c, -6 * h * c, 2 * h * h * c},
        {-12 * c, -6 * h * c, 12 * c, -6 * h * c}, {6 * h * c, 2 * h * h * c, -6 * h * c, 4 * h * h * c}}};
    const auto rows = std::size_t(mUnknowns);
    mBase.assign(rows * (kBand + 1), 0.0);
    mBand.assign(rows * (kBand + 1), 0.0);
    for (auto& r : mRhs) r.assign(rows, 0.0);
    mScratch.assign(rows, 0.0);
    for (auto& u : mU) u.assign(std::size_t(2 * (elements + 1)), 0.0);
    const std::array<double, 4> none{};
    mBand.swap(mBase); // scatter() writes mBand: build the base there
    for (int e = 0; e < mElements; ++e) scatter(e, mElement, none, none);
    mBand.swap(mBase);
    for (auto& r : mRhs) r.assign(rows, 0.0);
}

std::array<double, 4> WinklerBeam::shape(double t, double h) noexcept
{
    const double t2 = t * t, t3 = t2 * t;
    return {1.0 - 3.0 * t2 + 2.0 * t3, h * (t - 2.0 * t2 + t3), 3.0 * t2 - 2.0 * t3, h * (t3 - t2)};
}

void WinklerBeam::begin() noexcept
{
    std::copy(mBase.begin(), mBase.end(), mBand.begin());
    mFactored = false;
    mPinned = false;
    for (auto& r : mRhs) std::fill(r.begin(), r.end(), 0.0);
    mStartFoundation = Local{};
    mStartLoad = {};
}

void WinklerBeam::scatter(
    int e, const Local& k, const std::array<double, 4>& f1, const std::array<double, 4>& f2) noexcept
{
    constexpr int W = kBand + 1;
    if (e == 0 && &k != &mElement) { // element 0's foundation, kept whole for the clamp's reaction
        for (std::size_t i = 0; i < 4; ++i) {
            for (std::size_t j = 0; j <= i; ++j) {
                mStartFoundation[i][j] += k[i][j];
                if (j != i) mStartFoundation[j][i] += k[i][j];
            }
            mStartLoad[0][i] += f1[i];
            mStartLoad[1][i] += f2[i];
        }
    }
    for (int i = 0; i < 4; ++i) {
        const int gi = 2 * e + i - mOffset;
        if (gi < 0) continue;
        mRhs[0][std::size_t(gi)] += f1[std::size_t(i)];
        mRhs[1][std::size_t(gi)] += f2[std::size_t(i)];
        for (int j = 0; j <= i; ++j) {
            const int gj = 2 * e + j - mOffset;
            if (gj < 0) continue;
            mBand[std::size_t(gi * W + (gi - gj))] += k[std::size_t(i)][std::size_t(j)];
        }
    }
}

void WinklerBeam::addEndForce(double f1, double f2) noexcept
{
    const auto w = std::size_t(2 * mElements - mOffset);
    mRhs[0][w] += f1;
    mRhs[1][w] += f2;
}

void WinklerBeam::pinEnd(double w1, double w2) noexcept
{
    // The end's deflection is unknown g; its couplings move to the right-hand side
    // (rows g − B .. g + 1 of the symmetric band) and its row becomes w_g = value.
    constexpr int W = kBand + 1;
    const int g = 2 * mElements - mOffset;
    const double value[2] = {w1, w2};
    for (int j = 1; j <= kBand && g - j >= 0; ++j) {
        double& a = mBand[std::size_t(g * W + j)]; // A(g, g − j)
        for (std::size_t c = 0; c < 2; ++c) mRhs[c][std::size_t(g - j)] -= a * value[c];
        a = 0.0;
    }
    if (g + 1 < mUnknowns) {
        double& a = mBand[std::size_t((g + 1) * W + 1)]; // A(g + 1, g)
        for (std::size_t c = 0; c < 2; ++c) mRhs[c][std::size_t(g + 1)] -= a * value[c];
        a = 0.0;
    }
    mBand[std::size_t(g * W)] = 1.0;
    for (std::size_t c = 0; c < 2; ++c) mRhs[c][std::size_t(g)] = value[c];
    mPinned = true;
}

bool WinklerBeam::solve() noexcept
{
    for (auto& u : mU) std::fill(u.begin(), u.end(), 0.0);
    mFactored = false;
    if (!choleskyBand<kBand>(mBand.data(), mUnknowns)) return false;
    mFactored = true;
    for (std::size_t c = 0; c < 2; ++c) {
        solveBand<kBand>(mBand.data(), mUnknowns, mRhs[c].data());
        for (int i = 0; i < mUnknowns; ++i) {
            if (!std::isfinite(mRhs[c][std::size_t(i)])) {
                for (auto& u : mU) std::fill(u.begin(), u.end(), 0.0);
                mFactored = false;
                return false;
            }
            mU[c][std::size_t(i + mOffset)] = mRhs[c][std::size_t(i)];
        }
    }
    return true;
}

void WinklerBeam::deflectionAt(double x, double& w1, double& w2) const noexcept
{
    const int e = std::clamp(int(std::floor(x / mH)), 0, mElements - 1);
    const std::array<double, 4> n = shape(std::clamp((x - e * mH) / mH, 0.0, 1.0), mH);
    w1 = w2 = 0.0;
    for (int i = 0; i < 4; ++i) {
        w1 += n[std::size_t(i)] * mU[0][std::size_t(2 * e + i)];
        w2 += n[std::size_t(i)] * mU[1][std::size_t(2 * e + i)];
    }
}

void WinklerBeam::startReaction(double& f1, double& f2, double& m1, double& m2) const noexcept
{
    f1 = f2 = m1 = m2 = 0.0;
    if (!mClamped) return;
    // R = K·u − f on the clamped unknowns, which only element 0 reaches (u = 0 there).
    double r[2][2] = {};
    for (std::size_t c = 0; c < 2; ++c) {
        for (std::size_t a = 0; a < 2; ++a) {
            double s = -mStartLoad[c][a];
            for (std::size_t b = 2; b < 4; ++b) s += (mElement[a][b] + mStartFoundation[a][b]) * mU[c][b];
            r[c][a] = s;
        }
    }
    f1 = r[0][0], m1 = r[0][1], f2 = r[1][0], m2 = r[1][1];
}

double WinklerBeam::startTranslationStiffness() noexcept
{
    if (!mClamped || !mFactored) return 0.0;
    // Translate the start by 1 with its slope held: the free unknowns answer
    // K_ff·x = −K_f0, and the start's force is K_00 + K_0f·x. Only element 0 couples
    // the start's deflection (local 0) to the free unknowns (local 2 and 3).
    const auto k = [&](std::size_t a, std::size_t b) { return mElement[a][b] + mStartFoundation[a][b]; };
    std::fill(mScratch.begin(), mScratch.end(), 0.0);
    mScratch[0] = -k(2, 0);
    mScratch[1] = -k(3, 0);
    if (mPinned && mElements == 1) mScratch[0] = 0.0; // the pinned end stays where it is held
    solveBand<kBand>(mBand.data(), mUnknowns, mScratch.data());
    const double stiffness = k(0, 0) + k(0, 2) * mScratch[0] + k(0, 3) * mScratch[1];
    return std::isfinite(stiffness) ? std::max(0.0, stiffness) : 0.0;
}

} // namespace voxhap::haptic
