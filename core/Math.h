// SPDX-License-Identifier: Apache-2.0
/// @file Math.h
/// @brief The small value types used across voxhap (Eigen aliases).
///
/// World space is patient LPS in millimetres (architecture.md "Conventions").
#pragma once

#include <Eigen/Core>
#include <Eigen/LU> // for determinant() and inverse() of the 3x3 direction matrices

namespace voxhap {

using Vec3d = Eigen::Vector3d;
using Vec3i = Eigen::Vector3i;
using Mat3d = Eigen::Matrix3d;

/// @brief pi, for the degree conversions the CLI and phantoms need.
inline constexpr double kPi = 3.14159265358979323846;

inline constexpr double degToRad(double deg) { return deg * kPi / 180.0; }

} // namespace voxhap
