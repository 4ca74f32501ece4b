// SPDX-License-Identifier: Apache-2.0
/// @file CutTrack.cpp
#include "haptic/beam/CutTrack.h"

#include "core/Errors.h"

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

CutTrack::CutTrack(double stepMm, double maxLengthMm) : mStep(stepMm)
{
    if (!(stepMm > 0.0) || !std::isfinite(stepMm) || !(maxLengthMm > 0.0) || !std::isfinite(maxLengthMm))
        throw ValueError("cut track: the step and the length must be positive");
    const auto n = std::size_t(std::ceil(maxLengthMm / stepMm)) + 2;
    mPoints.assign(n, Vec3d::Zero());
    mModulus.assign(n, 0.0);
}

void CutTrack::start(const Vec3d& entry, double modulusNPerMm2, const Vec3d& ahead) noexcept
{
    mPoints[0] = entry;
    mModulus[0] = modulusNPerMm2;
    mCount = 1;
    mFront = entry;
    mFrontTau = 0.0;
    mFrontModulus = modulusNPerMm2;
    mAhead = ahead;
}

void CutTrack::sample(double tau, Vec3d& p, double& k) const noexcept
{
    if (tau >= mFrontTau) {
        p = mFront + (tau - mFrontTau) * mAhead;
        k = mFrontModulus;
        return;
    }
    const double end = lengthMm();
    if (tau >= end) { // between the deepest point and the front: one straight cut
        const double f = mFrontTau > end ? (tau - end) / (mFrontTau - end) : 0.0;
        const std::size_t last = std::size_t(mCount - 1);
        p = mPoints[last] + f * (mFront - mPoints[last]);
        k = mModulus[last] + f * (mFrontModulus - mModulus[last]);
        return;
    }
    const double s = std::max(0.0, tau) / mStep;
    const int j = std::min(mCount - 2, int(s));
    const double f = s - j;
    p = mPoints[std::size_t(j)] + f * (mPoints[std::size_t(j + 1)] - mPoints[std::size_t(j)]);
    k = mModulus[std::size_t(j)] + f * (mModulus[std::size_t(j + 1)] - mModulus[std::size_t(j)]);
}

} // namespace voxhap::haptic
