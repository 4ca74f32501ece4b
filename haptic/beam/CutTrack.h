// SPDX-License-Identifier: Apache-2.0
/// @file CutTrack.h
/// @brief The track a needle's tip cuts through the tissue (physics.md §9.3):
/// points at equal arc lengths from the skin entry, each with the foundation
/// modulus of the tissue it was cut in. The shaft follows it ("follow the
/// leader"): the point of the shaft at arc length τ below the skin rests on the
/// track's point at τ.
#pragma once

#include "core/Math.h"

#include <vector>

namespace voxhap::haptic {

class CutTrack {
public:
    /// @param stepMm arc length between points [mm]
    /// @param maxLengthMm the longest track (the needle's length): the buffers' size
    /// @throw ValueError on a step or length that is not positive and finite
    CutTrack(double stepMm, double maxLengthMm);

    void clear() noexcept { mCount = 0; }
    bool empty() const noexcept { return mCount == 0; }
    int count() const noexcept { return mCount; }
    int capacity() const noexcept { return int(mPoints.size()); }
    double stepMm() const noexcept { return mStep; }
    /// @brief Arc length from the entry to the deepest point cut [mm].
    double lengthMm() const noexcept { return mCount > 0 ? (mCount - 1) * mStep : 0.0; }
    const Vec3d& point(int j) const noexcept { return mPoints[std::size_t(j)]; }
    double modulus(int j) const noexcept { return mModulus[std::size_t(j)]; }

    /// @brief Start at the skin entry. Clears any track.
    void start(const Vec3d& entry, double modulusNPerMm2) noexcept;
    /// @brief The next point, one step deeper. @return false when full.
    bool append(const Vec3d& p, double modulusNPerMm2) noexcept;
    /// @brief Position and modulus at arc length @p tau (linear between points).
    /// Beyond the deepest point: uncut tissue ahead of the tip, along @p ahead (a
    /// unit vector) from it, with its modulus. Requires a started track.
    void sample(double tau, const Vec3d& ahead, Vec3d& p, double& k) const noexcept;

private:
    double mStep;
    std::vector<Vec3d> mPoints;
    std::vector<double> mModulus;
    int mCount = 0;
};

} // namespace voxhap::haptic
