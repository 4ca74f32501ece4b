// SPDX-License-Identifier: Apache-2.0
/// @file StoredPrecision.h
/// @brief Tolerances of the DICOM geometry checks derived from the digits a
/// writer stored.
///
/// Positions, direction cosines and pixel spacings are decimal strings (DS,
/// at most 16 characters). A writer that keeps one decimal ("-12.5") rounds
/// every coordinate by up to 0.05 mm; one that writes %.14g rounds by 1e-14.
/// A fixed tolerance either refuses the first (a plain MR stack stored to
/// 0.1 mm looked "tilted by 0.002°") or waves through real changes in the
/// second. So each check tolerates what the stored digits cannot resolve,
/// plus a small floor for the arithmetic of the scanner itself.
///
/// The unit of a value is the value of its last stored digit: "12.5" → 0.1,
/// "9.0584602e-009" → 1e-16; a whole number ("-130", "0", "1") has none, for
/// writers drop trailing zeros ("-130" beside "-81.599998474121" is exact). A
/// series' unit is the FINEST unit among all its strings: the finest digit
/// seen is the writer's precision. No decimal anywhere: the floors alone.
#pragma once

#include <string>

namespace voxhap::volume {

/// @brief The value of the last digit of decimal string @p text
/// (0 if it is not a number or a whole number).
double lastDigitUnit(const std::string& text);

/// @brief The finest unit among the backslash-separated numbers of @p text
/// (0 if none is a number).
double finestUnit(const std::string& text);

/// @brief Floor of the position tolerance [mm] [chosen]: 0.01 mm, ten times
/// the single-precision error of a coordinate 1 m from the isocentre
/// (6e-5 mm) and a fiftieth of a fine 0.5 mm pixel.
inline constexpr double kPositionFloorMm = 0.01;

/// @brief Floor of the direction tolerance [chosen]: 1e-4 (0.006°), the
/// tolerance voxhap used before it looked at the digits; far below any real
/// change of orientation between slices.
inline constexpr double kDirectionFloor = 1e-4;

/// @brief How far two stored positions may disagree along one direction
/// [mm]: each coordinate is off by at most half its unit, so a difference
/// projected on a unit vector by at most √3 · unit; plus the floor.
double positionToleranceMm(double positionUnit);

/// @brief How far two stored unit directions may disagree (norm of the
/// difference): √3 · unit (two vectors, each off by √3/2 · unit), at least the floor.
double directionTolerance(double orientationUnit);

/// @brief Drift off the normal allowed per mm along a stack before it counts
/// as a tilt [chosen]: the direction tolerance, at most 1e-3 (0.06°): direction
/// cosines stored with fewer than four decimals must not hide a gantry tilt.
inline constexpr double kMaxDriftPerMm = 1e-3;

} // namespace voxhap::volume
