// SPDX-License-Identifier: Apache-2.0
/// @file BlockDdaPeer.h
/// @brief The peer of the exact voxel traversal in `bench sampler`: a
/// two-level walk built only from OpenVDB parts, as a careful OpenVDB user
/// would write it. openvdb::math::DDA steps over 8³ blocks; inside a leaf a
/// voxel math::DDA reads the leaf's buffer directly; a tile (or background)
/// block is its one value times its chord. Same grid, same segments, same
/// voxel reading as haptic's exact-voxel strategy, so its sums must agree.
#pragma once

#include "haptic/materials/MaterialField.h"
#include "haptic/shaft/ShaftIntegration.h"

#include <memory>

namespace voxhap::bench {

class BlockDdaPeer {
public:
    /// @throw ValueError if @p field has no damping grid
    explicit BlockDdaPeer(const haptic::MaterialField& field);
    ~BlockDdaPeer();
    BlockDdaPeer(const BlockDdaPeer&) = delete;
    BlockDdaPeer& operator=(const BlockDdaPeer&) = delete;

    /// @brief ∫β ds along @p s [N·s/mm], the piecewise-constant (voxel) reading.
    double integrate(const haptic::Segment& s) noexcept;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace voxhap::bench
