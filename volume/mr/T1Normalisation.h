// SPDX-License-Identifier: Apache-2.0
/// @file T1Normalisation.h
/// @brief T1-weighted intensity → T1 [ms], normalised per scan from its own fat
/// and muscle (physics.md §5.1 rule).
///
/// T1 depends on how it was measured, and a T1-weighted image holds no T1 at
/// all, only a signal that falls as T1 rises. physics.md §5.1 therefore fixes
/// the scale per dataset: find fat and muscle in the scan itself and pin them
/// to the tissue table's T1 at the scan's field strength.
///
/// - Fat and muscle: a three-class Otsu split of the voxel intensities
///   (background and fluid / muscle / fat, which is brightest in T1w); the
///   reference intensity of each class is its exact median.
/// - Between the references [chosen]: intensity is taken as linear in the
///   relaxation rate R1 = 1/T1, which is what a short-TR (T1-weighted)
///   acquisition gives, S ∝ 1 − exp(−TR·R1) ≈ TR·R1 for TR ≪ T1. Linear in T1
///   instead would put CSF (dark) at a few hundred ms too short.
/// - Results are clamped to [kMinT1Ms, kMaxT1Ms]: below the fat line the rate
///   model runs to negative T1, and above CSF it has no support.
#pragma once

#include "volume/TissueTable.h"

#include <cstdint>
#include <optional>
#include <string>

namespace voxhap::volume {

class Volume;

/// Lowest T1 a normalised voxel takes [ms]: well below fat at 1.5 T (290 ms, §5.1).
inline constexpr double kMinT1Ms = 100.0;
/// Highest T1 a normalised voxel takes [ms]: above CSF at 1.5 T (4280 ms, §5.1).
inline constexpr double kMaxT1Ms = 5000.0;

/// @brief The per-scan fit, for metadata and reports.
struct T1wNormalisation {
    FieldStrength field = FieldStrength::T1_5;
    double fatIntensity = 0, muscleIntensity = 0;  ///< class medians [scanner units]
    double fatT1Ms = 0, muscleT1Ms = 0;            ///< the table's references [ms]
    double lowerThreshold = 0, upperThreshold = 0; ///< Otsu class boundaries [scanner units]
    std::int64_t fatVoxels = 0, muscleVoxels = 0;

    /// @brief T1 [ms] of intensity @p s, linear in 1/T1 through the two references, clamped.
    double t1Ms(double s) const;
};

/// @brief Fit the normalisation to the active voxels of @p v's t1 grid.
/// @param source names the file in error messages
/// @throw ValueError naming @p source if the grid has no t1 channel, too few
///        voxels, or no brighter fat class above a muscle class
T1wNormalisation fitT1wNormalisation(
    const Volume& v, const TissueTable& table, FieldStrength field, const std::string& source);

/// @brief Replace every active t1 value of @p v by its normalised T1 [ms] and
/// record the fit in the metadata (t1Units "ms", t1Kind, and t1_norm_* for display).
void applyT1wNormalisation(Volume& v, const T1wNormalisation& fit);

} // namespace voxhap::volume
