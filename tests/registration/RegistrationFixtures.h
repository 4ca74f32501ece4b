// SPDX-License-Identifier: Apache-2.0
/// @file RegistrationFixtures.h
/// @brief What the registration tests share: rotations by angle.
#pragma once

#include "core/Math.h"

#include <Eigen/Geometry>

namespace voxhap::test {

/// A rotation by @p degrees about x, then y, then z (world axes).
inline Mat3d rotationDeg(const Vec3d& degrees)
{
    constexpr double kPi = 3.14159265358979323846;
    const auto r = [](double deg, const Vec3d& axis) {
        return Eigen::AngleAxisd(deg * kPi / 180.0, axis).toRotationMatrix();
    };
    return r(degrees.z(), Vec3d::UnitZ()) * r(degrees.y(), Vec3d::UnitY()) * r(degrees.x(), Vec3d::UnitX());
}

} // namespace voxhap::test
