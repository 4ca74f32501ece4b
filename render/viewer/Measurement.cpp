// SPDX-License-Identifier: Apache-2.0
/// @file Measurement.cpp
#include "render/viewer/Measurement.h"

#include <Eigen/Geometry> // for cross

#include <cmath>
#include <numbers>

namespace voxhap::render {

double distanceMm(const Vec3d& a, const Vec3d& b) { return (b - a).norm(); }

std::optional<double> angleDeg(const Segment& s1, const Segment& s2)
{
    const Vec3d u = s1.b - s1.a, v = s2.b - s2.a;
    if (!(u.norm() > 0.0) || !(v.norm() > 0.0)) return std::nullopt;
    return std::atan2(u.cross(v).norm(), u.dot(v)) * 180.0 / std::numbers::pi;
}

} // namespace voxhap::render
