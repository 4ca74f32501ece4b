// SPDX-License-Identifier: Apache-2.0
/// @file Fusion.h
/// @brief One patient's CT and MR in one volume on the CT's grid: `hu` from the
/// CT, the MR registered and resampled as `t1` (a T1 map or a normalised
/// T1-weighted scan) or `intensity` (any other MR), with the registration's
/// record in the metadata (docs/reference.md "CT and MR fusion"). Labels come
/// after, from segmentation/FusedLabels.h, which reads both channels.
#pragma once

#include "registration/Registration.h"
#include "registration/Resample.h"
#include "volume/Volume.h"

#include <optional>
#include <string>

namespace voxhap::registration {

/// @brief Who a series belongs to, where its headers say (DICOM); empty fields are unknown.
struct PatientIdentity {
    std::string id;   ///< (0010,0020) PatientID
    std::string name; ///< (0010,0010) PatientName
};

struct FusionOptions {
    RegistrationOptions registration;
    std::string ctFile = "CT"; ///< the CT input as the user named it (messages, channel sources)
    std::string mrFile = "MR";
    std::string ctSource; ///< what was read from it ("DICOM series #2, 205 slices"); empty: the file alone
    std::string mrSource;
};

struct FusionResult {
    volume::Volume volume; ///< hu and t1 or intensity on the CT's grid, with the fusion record
    RegistrationResult registration;
    std::string transformText; ///< the .tfm ITK writes for it
    ResampleReport resample;
    double seconds = 0; ///< registration, resampling and the grids, from the loaded volumes
};

/// @brief Refuse inputs that cannot be one patient's CT and MR, naming the file:
/// a CT given as the MR or the other way round, an MR of one slice.
/// @throw ValueError "<file>: <why>"
void checkFusionInputs(const volume::Volume& ct, const volume::Volume& mr, const FusionOptions& options);

/// @brief Refuse two series whose PatientID or PatientName differ, comparing only
/// the fields both have (names without case and trailing '^' separators).
/// @throw ValueError naming both files and the field
void checkSamePatient(const PatientIdentity& ct, const PatientIdentity& mr, const FusionOptions& options);

/// @brief checkFusionInputs, register, resample, and build the fused volume.
/// @throw ValueError from the checks and the registration's refusals, prefixed by the MR file
FusionResult fuse(const volume::Volume& ct, const volume::Volume& mr, const FusionOptions& options = {});

} // namespace voxhap::registration
