// SPDX-License-Identifier: Apache-2.0
/// @file PatientFusion.h
/// @brief One patient's CT and MR files to one fused volume: both loaded, the
/// patient checked, the MR registered and resampled onto the CT's grid
/// (registration/Fusion.h), labelled from both scans (segmentation/FusedLabels.h),
/// and written as a .vdb with its ITK .tfm beside it. What `voxhap fuse` and
/// Python's `voxhap.fuse` run (docs/reference.md "CT and MR fusion").
#pragma once

#include "registration/Fusion.h"
#include "segmentation/FusedLabels.h"
#include "volume/VolumeFile.h"

#include <filesystem>
#include <string>

namespace voxhap::fusion {

/// @brief How the optimiser's start is chosen.
enum class Start {
    Auto,     ///< the header geometry when both DICOM series share a FrameOfReferenceUID, else the search
    Search,   ///< the best of the 24 axis-aligned turns, by the metric
    Geometry, ///< the header geometry as it is
};

struct PatientFusionOptions {
    std::filesystem::path ct, mr;
    volume::LoadOptions ctLoad; ///< its dicom.series selects the CT's series
    volume::LoadOptions mrLoad; ///< dicom.series and dicom.volume select the MR's
    registration::RegistrationOptions registration;
    Start start = Start::Auto;
    bool differentPatients = false;             ///< fuse although PatientID or PatientName differ
    const volume::TissueTable* table = nullptr; ///< the built-in table when null
};

struct PatientFusion {
    volume::Volume volume; ///< hu, t1 or intensity, label on the CT's grid, with the record
    registration::RegistrationResult registration;
    registration::ResampleReport resample;
    segmentation::FusedLabelReport labels;
    std::string transformText; ///< the .tfm ITK writes
    std::string ctSource, mrSource;
    double loadSeconds = 0;
};

/// @brief Load, check, register, resample and label.
/// @throw IoError or ValueError with one line naming the file and the reason
PatientFusion fusePatient(const PatientFusionOptions& options);

/// @brief Write @p f.volume to @p vdb and its transform beside it (the same
/// name with .tfm), both or neither.
/// @return the transform file's path
/// @throw IoError naming the file
std::filesystem::path writeFusion(const PatientFusion& f, const std::filesystem::path& vdb);

} // namespace voxhap::fusion
