// SPDX-License-Identifier: Apache-2.0
/// @file PlaneCrossingSum.h
/// @brief An independent check of the exact voxel sums in `bench sampler`:
/// ∫β ds of the voxel reading from every crossing of a voxel-face plane along
/// the segment, sorted, each interval taking the voxel at its midpoint, in long
/// double. No walk at all; the grid's affine map applied as the walks apply it
/// (bench/BlockDdaPeer.h, haptic's AffineIndexMap), so all three see the same
/// index-space segment and differ only by their own round-off.
#pragma once

#include "haptic/materials/MaterialField.h"
#include "haptic/shaft/ShaftIntegration.h"

#include <memory>

namespace voxhap::bench {

class PlaneCrossingSum {
public:
    /// @throw ValueError if @p field has no damping grid
    explicit PlaneCrossingSum(const haptic::MaterialField& field);
    ~PlaneCrossingSum();
    PlaneCrossingSum(const PlaneCrossingSum&) = delete;
    PlaneCrossingSum& operator=(const PlaneCrossingSum&) = delete;

    /// @brief ∫β ds along @p s [N·s/mm] (allocates: not for timing).
    double integrate(const haptic::Segment& s) const;
    /// @brief The largest finite |β| of the grid [N·s/mm²]: β_max·length bounds any sum.
    double largestValue() const;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace voxhap::bench
