// SPDX-License-Identifier: Apache-2.0
/// @file SliceStack.h
/// @brief The geometry of a stack of 2D slices (a DICOM series): ordering by
/// position along the slice normal, and the checks that decide whether the
/// stack is a uniform 3D grid (regular spacing, no missing slice, no tilt).
///
/// Pure geometry, no file access: DicomSeries fills it from the headers.
#pragma once

#include "core/Math.h"

#include <string>
#include <vector>

namespace voxhap::volume {

/// @brief One slice: where it is and where it came from.
struct SlicePlacement {
    Vec3d position{0, 0, 0}; ///< ImagePositionPatient: centre of the first pixel [mm, LPS]
    std::size_t source = 0;  ///< index of the slice in the caller's list
};

/// @brief How far slice positions may stray from a uniform grid and still be
/// taken as uniform, when nothing better is known. The DICOM loader derives
/// its tolerance from the digits the positions were stored with instead
/// (StoredPrecision.h).
inline constexpr double kSlicePositionToleranceMm = 0.05;

/// @brief What the ordered positions say about the stack.
struct SliceStackGeometry {
    std::vector<SlicePlacement> slices; ///< ascending position along the normal
    Vec3d normal{0, 0, 1};              ///< row × column direction (unit)
    double step = 0;                    ///< slice step along the normal [mm]: the lower median step
    bool uniform = true;                ///< every step equals `step` within the tolerance, no tilt
    int missingSlices = 0;              ///< slices absent where the steps are whole multiples of `step`
    double tiltDeg = 0;                 ///< angle between the stack axis and the normal [deg]
    bool tilted = false;                ///< in-plane drift of the positions beyond the tolerance
    std::string problem;                ///< why the stack is not a uniform grid, empty if it is
};

/// @brief Order slices along @p normal and check their spacing and alignment.
/// @param slices    positions in any order (file order is never used)
/// @param normal    unit slice normal (row × column direction cosines)
/// @param toleranceMm positions within this of the uniform grid count as uniform
/// @param directionTolerance how far the stored normal may be off (norm of the
///        difference of unit vectors): a position |d| mm along the stack may
///        drift |d|·directionTolerance off the normal line without a tilt
/// @throw ValueError if two slices share a position along the normal
SliceStackGeometry orderSlices(std::vector<SlicePlacement> slices, const Vec3d& normal,
    double toleranceMm = kSlicePositionToleranceMm, double directionTolerance = 0.0);

} // namespace voxhap::volume
