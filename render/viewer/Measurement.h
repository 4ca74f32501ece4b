// SPDX-License-Identifier: Apache-2.0
/// @file Measurement.h
/// @brief The measuring tools of a CT console, as the viewer offers them for
/// path planning: the distance between two points and the angle between two
/// segments, both in patient space (mm, LPS), whatever the view they were
/// picked on.
#pragma once

#include "core/Math.h"

#include <optional>

namespace voxhap::render {

/// @brief A segment between two picked points [mm, LPS].
struct Segment {
    Vec3d a{0, 0, 0}, b{0, 0, 0};
    double lengthMm() const { return (b - a).norm(); }
};

/// @brief Euclidean distance between @p a and @p b [mm].
double distanceMm(const Vec3d& a, const Vec3d& b);

/// @brief Angle between the directions a→b of two segments [deg], in [0, 180].
/// Computed as atan2(|u × v|, u · v), which stays accurate near 0° and 180°
/// where acos of the dot product loses half its digits.
/// @return nullopt if either segment has zero length (no direction).
std::optional<double> angleDeg(const Segment& s1, const Segment& s2);

} // namespace voxhap::render
