// SPDX-License-Identifier: Apache-2.0
/// @file SliceResample.h
/// @brief Resample an irregular slice stack (uneven steps, missing slices,
/// gantry tilt) onto planes perpendicular to the slice normal: bilinear within
/// each input slice, linear between the two slices that bracket the plane.
#pragma once

#include "volume/dicom/detail/SliceStack.h"

#include <Eigen/Core>

namespace voxhap::volume {

/// @brief Samples output planes from ordered input slices.
/// @note Thread-safe for concurrent sample() calls (read-only state).
class SliceResampler {
public:
    /// @param stack   ordered slices (orderSlices); input slice k is stack.slices[k]
    /// @param input   stack.slices.size() images of nx × ny values, column fastest, in that order
    /// @param row     unit direction of increasing column index [LPS]
    /// @param col     unit direction of increasing row index [LPS]
    /// @param spacing pixel size along row and col [mm]
    /// @param outside value for points outside every slice (air)
    SliceResampler(const SliceStackGeometry& stack, const float* input, int nx, int ny, const Vec3d& row,
        const Vec3d& col, const Eigen::Vector2d& spacing, float outside);

    /// @brief Fill @p out (@p outNx × @p outNy, x fastest) with the plane whose
    /// first pixel centre is at @p planeOrigin, pixels spaced as the input's.
    void sample(const Vec3d& planeOrigin, int outNx, int outNy, float* out) const;

private:
    float bilinear(std::size_t slice, double u, double v) const;

    const SliceStackGeometry& mStack;
    const float* mInput;
    int mNx, mNy;
    Vec3d mRow, mCol;
    Eigen::Vector2d mSpacing;
    float mOutside;
    std::vector<double> mAlong; ///< each slice's position along the normal [mm]
};

} // namespace voxhap::volume
