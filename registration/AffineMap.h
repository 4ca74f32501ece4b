// SPDX-License-Identifier: Apache-2.0
/// @file AffineMap.h
/// @brief A 3D affine point map y = A·x + t in world space (LPS mm), the form
/// every registration stage of this library reduces to. Header-only (Eigen).
///
/// The map of a CT–MR registration is `mr_from_ct`: it takes a point of the CT
/// (the fixed image) to the same anatomy in the MR (the moving image). That is
/// ITK's transform direction, fixed to moving, the one a resampler needs and the
/// one a `.tfm` file holds (docs/reference.md "CT and MR fusion").
#pragma once

#include "core/Math.h"

#include <Eigen/Dense>

namespace voxhap::registration {

using Mat4d = Eigen::Matrix4d;

struct AffineMap {
    Mat3d linear = Mat3d::Identity(); ///< A
    Vec3d offset = Vec3d::Zero();     ///< t [mm]

    Vec3d apply(const Vec3d& x) const { return linear * x + offset; }
    /// @brief The inverse map (A must be invertible).
    AffineMap inverse() const
    {
        const Mat3d inv = linear.inverse();
        return {inv, -(inv * offset)};
    }
    /// @brief this ∘ other: x ↦ this(other(x)).
    AffineMap after(const AffineMap& other) const { return {linear * other.linear, linear * other.offset + offset}; }
    /// @brief The homogeneous 4×4 matrix [A t; 0 0 0 1].
    Mat4d matrix() const
    {
        Mat4d m = Mat4d::Identity();
        m.topLeftCorner<3, 3>() = linear;
        m.topRightCorner<3, 1>() = offset;
        return m;
    }
    static AffineMap fromMatrix(const Mat4d& m) { return {m.topLeftCorner<3, 3>(), m.topRightCorner<3, 1>()}; }
    /// @brief A rotation @p r about the point @p centre, then a shift @p shift.
    static AffineMap rotationAbout(const Mat3d& r, const Vec3d& centre, const Vec3d& shift = Vec3d::Zero())
    {
        return {r, centre - r * centre + shift};
    }
};

} // namespace voxhap::registration
