// SPDX-License-Identifier: Apache-2.0
/// @file Tolerances.h
/// @brief Named test tolerances, each with the reason for its size (style.md §6).
#pragma once

#include "core/Math.h"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

namespace voxhap::test {

/// Index <-> world round trip through a 4x4 double affine map and its inverse:
/// a few ulps of the largest coordinate (~1e3 mm) per multiply-add, 1e-9 mm is
/// far below any voxel and far above double round-off.
inline constexpr double kRoundTripMm = 1e-9;

/// Spacing and direction recovered from a transform: products and square roots
/// of doubles of order 1, so round-off of order 1e-15; 1e-12 leaves headroom.
inline constexpr double kGeometryRelative = 1e-12;

/// Tissue table values converted from their file units: one multiplication by
/// an exact power of ten, so the relative error is a few ulps.
inline constexpr double kUnitConversionRelative = 1e-12;

/// Positions, orientations and spacings travel as DICOM decimal strings of at
/// most 16 characters ("1.07421875", "484.91"): parsed into doubles they carry
/// ~1e-13 mm of rounding on coordinates of order 100 mm, and differences of
/// them (the slice step) likewise. 1e-6 mm is ample and far below any pixel.
inline constexpr double kDicomDecimalMm = 1e-6;

/// A voxelised boundary lies within half a voxel of the analytic one: voxels
/// take the tissue at their centre, and a centre is at most half a voxel from
/// any point of its cell along an axis.
inline double halfVoxel(double spacing) { return 0.5 * spacing; }

/// @brief Eigen vectors equal within @p tol per component, naming the component that differs.
inline testing::AssertionResult nearVec(const Vec3d& a, const Vec3d& b, double tol)
{
    for (int i = 0; i < 3; ++i) {
        if (!(std::abs(a[i] - b[i]) <= tol)) {
            std::ostringstream os;
            os << "component " << i << ": " << a[i] << " vs " << b[i] << " (|diff| " << std::abs(a[i] - b[i]) << " > "
               << tol << ")";
            return testing::AssertionFailure() << os.str();
        }
    }
    return testing::AssertionSuccess();
}

} // namespace voxhap::test

namespace voxhap::test {

/// Exact traversal of a piecewise-constant field: the only error is round-off
/// in the chord arithmetic, ~1e-15 relative per voxel over a few hundred
/// voxels; physics.md §7 R1 asks for 1e-9 relative.
inline constexpr double kExactRelative = 1e-9;

/// Chord lengths summed over a shaft equal its length to this (physics.md §6.4).
inline constexpr double kChordSumRelative = 1e-12;

} // namespace voxhap::test
