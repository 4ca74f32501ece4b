// SPDX-License-Identifier: Apache-2.0
/// @file ModalityInference.h
/// @brief CT or MR for formats that do not say (NIfTI, NRRD, MetaImage), from
/// the values themselves.
///
/// The rule:
/// - CT: negative values with air — at least kMinAirFraction of the voxels
///   between −1200 and −900 HU (air is −1000 HU; scanners' noise and
///   reconstruction spread it by tens of HU) — and soft tissue or water, at
///   least kMinWaterFraction between −200 and +200 HU.
/// - MR: no value below zero, or negative values only as interpolation
///   ringing (the minimum above −kMaxRingingFraction of the maximum), as a
///   magnitude image's intensities are.
/// - Anything else (negative values without air at −1000: a brain-extracted
///   CT, a phase image, a z-scored MR) is not decided: the loader refuses it
///   and names --channel. The data cannot tell T1- from T2- or PD-weighting:
///   that comes from a BIDS sidecar or the user (MrWeighting.h), never from
///   image statistics.
/// Known limit: CT stored without its rescale intercept (unsigned, air at 0,
/// water at 1024) has no negative value and reads as MR; --channel hu declares it.
#pragma once

#include "volume/Volume.h"

#include <cstdint>
#include <string>

namespace voxhap::volume {

/// @name Thresholds of the rule.
/// @{
/// Fraction of voxels at air (−1200..−900 HU) that marks CT [chosen]: 0.1 %.
/// Even a tightly cropped body CT keeps air in the lungs, bowel or around the
/// skin; an MR has no value there at all.
inline constexpr double kMinAirFraction = 1e-3;
/// Fraction of voxels at water or soft tissue (−200..200 HU) that marks CT
/// [chosen]: 1 %. Every CT of a body holds far more.
inline constexpr double kMinWaterFraction = 1e-2;
/// Negative values of an MR image that are interpolation ringing [chosen]:
/// down to 5 % of the maximum (sinc and spline resampling overshoot by a few %).
inline constexpr double kMaxRingingFraction = 0.05;
/// @}

/// @brief The verdict.
struct ModalityGuess {
    enum class Kind {
        Ct,
        Mr,
        Unknown
    } kind = Kind::Unknown;
    std::string reason; ///< one line: the figures that decided
};

/// @brief Apply the rule to every active value of @p grid (a FloatGrid of raw
/// values; read with no air threshold, so that the air counts).
/// @throw ValueError if @p grid is not a FloatGrid
ModalityGuess inferModality(const openvdb::GridBase& grid);

} // namespace voxhap::volume
