// SPDX-License-Identifier: Apache-2.0
/// @file CutTrack.h
/// @brief The track a needle's tip cuts through the tissue (physics.md §9.3), in
/// the tissue's rest frame: points at equal arc lengths from the skin entry, each
/// with the foundation modulus of the tissue it was cut in, and the cut front,
/// the deepest point cut, which advances continuously along the tip's heading.
/// The shaft follows it ("follow the leader"): the point of the shaft at arc
/// length τ below the skin rests on the track's point at τ.
#pragma once

#include "core/Math.h"

#include <vector>

namespace voxhap::haptic {

class CutTrack {
public:
    /// @param stepMm arc length between stored points [mm]
    /// @param maxLengthMm the longest track (the needle's length): the buffers' size
    /// @throw ValueError on a step or length that is not positive and finite
    CutTrack(double stepMm, double maxLengthMm);

    void clear() noexcept { mCount = 0; }
    bool empty() const noexcept { return mCount == 0; }
    int count() const noexcept { return mCount; }
    int capacity() const noexcept { return int(mPoints.size()); }
    double stepMm() const noexcept { return mStep; }
    /// @brief Arc length from the entry to the deepest stored point [mm].
    double lengthMm() const noexcept { return mCount > 0 ? (mCount - 1) * mStep : 0.0; }
    /// @brief Arc length from the entry to the cut front [mm] (≥ lengthMm()).
    double frontMm() const noexcept { return mCount > 0 ? mFrontTau : 0.0; }
    const Vec3d& front() const noexcept { return mFront; }
    /// @brief The direction the front last advanced in: where uncut tissue lies ahead.
    const Vec3d& ahead() const noexcept { return mAhead; }
    /// @brief Modulus of the tissue at the cut front, the tissue being cut [N/mm²].
    double frontModulus() const noexcept { return mFrontModulus; }
    const Vec3d& point(int j) const noexcept { return mPoints[std::size_t(j)]; }
    double modulus(int j) const noexcept { return mModulus[std::size_t(j)]; }

    /// @brief Start at the skin entry, the uncut tissue ahead along @p ahead (a unit
    /// vector). Clears any track.
    void start(const Vec3d& entry, double modulusNPerMm2, const Vec3d& ahead) noexcept;
    /// @brief Cut on to arc length @p tau (nothing when @p tau is not beyond the
    /// front), the tip's heading having gone from the unit @p fromHeading (the last
    /// solve's) to the unit @p heading (this one's). The front moves along their mean
    /// (the trapezoid rule: the path's error falls as the square of the advance per
    /// call, physics.md §9.3), @p heading becomes ahead(), and a point is stored at
    /// each step passed, with @p modulusAt(point) [N/mm²].
    /// @return whether the front moved
    template <typename ModulusAt>
    bool cut(double tau, const Vec3d& fromHeading, const Vec3d& heading, ModulusAt&& modulusAt) noexcept;
    /// @brief Position and modulus at arc length @p tau (linear between points, and
    /// from the deepest point to the front). Beyond the front: uncut tissue, along
    /// ahead() from it, with the front's modulus. Requires a started track.
    void sample(double tau, Vec3d& p, double& k) const noexcept;

private:
    double mStep;
    std::vector<Vec3d> mPoints;
    std::vector<double> mModulus;
    int mCount = 0;
    Vec3d mFront{0, 0, 0}, mAhead{0, 0, 1};
    double mFrontTau = 0.0, mFrontModulus = 0.0;
};

template <typename ModulusAt>
bool CutTrack::cut(double tau, const Vec3d& fromHeading, const Vec3d& heading, ModulusAt&& modulusAt) noexcept
{
    if (mCount == 0 || !(tau > mFrontTau)) return false;
    const Vec3d from = mFront;
    const double tau0 = mFrontTau;
    const Vec3d mean = fromHeading + heading;
    const double n = mean.norm();
    const Vec3d chord = n > 1e-9 ? Vec3d(mean / n) : heading; // a reversal (n = 0) cannot be averaged
    while (mCount < capacity() && mCount * mStep <= tau) {
        const Vec3d p = from + (mCount * mStep - tau0) * chord;
        mPoints[std::size_t(mCount)] = p;
        mModulus[std::size_t(mCount)] = modulusAt(p);
        ++mCount;
    }
    mFront = from + (tau - tau0) * chord;
    mFrontTau = tau;
    mAhead = heading;
    mFrontModulus = modulusAt(mFront);
    return true;
}

} // namespace voxhap::haptic
