// SPDX-License-Identifier: Apache-2.0
/// @file MrMaterial.h
/// @brief What an MR image becomes: T1 in ms only where there is T1, an
/// intensity grid everywhere else, and the air around the body inactive.
///
/// Every MR loader (DICOM, and NIfTI, NRRD, MetaImage once the data say MR)
/// delivers the stored intensities in the `intensity` channel and calls
/// assignMrMaterial() with the weighting its headers gave (MrWeighting.h):
/// 1. the air background of magnitude images is made inactive
///    (MrBackground.h); phase images have no such background and keep every voxel;
/// 2. a T1 map moves to `t1` as it is [ms];
/// 3. a T1-weighted image of a trunk is normalised per scan
///    (T1Normalisation.h, physics.md §5.1) and moves to `t1` [ms]; a body
///    narrower than a trunk (BodyWidth.h: a head or a limb, whose brightest
///    class is not fat) or a scan without fat and muscle classes stays
///    `intensity`, and the metadata say why;
/// 4. anything else (PD, T2, FLAIR, diffusion, field maps, unknown) stays
///    `intensity`, which no force law reads as T1.
/// The metadata record the weighting, the fields that decided it and every step.
#pragma once

#include "volume/TissueTable.h"
#include "volume/Volume.h"
#include "volume/mr/MrBackground.h"
#include "volume/mr/MrWeighting.h"

#include <optional>
#include <string>

namespace voxhap::volume {

/// @brief The user's say over the rule.
struct MrMaterialOptions {
    /// The values are T1 in ms whatever the headers say (--t1-map).
    bool t1Map = false;
    /// Declare the image T1-weighted whatever the headers say (--t1-weighted);
    /// recorded in the metadata as a declaration.
    bool t1Weighted = false;
    /// T1-weighted intensities become T1 [ms] (off: they stay `intensity`).
    bool normaliseT1Weighted = true;
    /// Make the air background inactive (off: every voxel above 0 stays active).
    bool removeBackground = true;
};

/// @brief What assignMrMaterial decided, for reports.
struct MrMaterialReport {
    MrWeighting weighting;                        ///< as used (after any declaration)
    Channel channel = Channel::Intensity;         ///< where the values ended
    std::optional<MrBackgroundResult> background; ///< when the background rule ran
    std::string note;                             ///< one line: the normalisation, or why the values are not T1
};

/// @brief Steps 1–4 above on @p v, whose raw MR intensities are in the
/// intensity channel. A T1-weighted image is normalised at the field strength
/// the metadata hold (recordFieldStrength, VolumeMetadata.h); a scan at a
/// field that is neither 1.5 T nor 3 T is not, and says why.
/// @param weighting     the rule's verdict from the headers
/// @param source        names the input in messages
/// @throw ValueError if @p v has no intensity channel
MrMaterialReport assignMrMaterial(
    Volume& v, MrWeighting weighting, const MrMaterialOptions& options, const std::string& source);

} // namespace voxhap::volume
