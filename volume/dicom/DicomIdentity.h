// SPDX-License-Identifier: Apache-2.0
/// @file DicomIdentity.h
/// @brief Who a DICOM file belongs to and in which frame of reference: read to
/// compare two series (a CT and an MR to fuse), never stored with a volume
/// (VolumeMetadata holds no patient identity).
#pragma once

#include <filesystem>
#include <string>

namespace voxhap::volume {

struct DicomIdentity {
    std::string patientId;           ///< (0010,0020) PatientID, trimmed; empty when absent
    std::string patientName;         ///< (0010,0010) PatientName, trimmed
    std::string frameOfReferenceUid; ///< (0020,0052) FrameOfReferenceUID
};

/// @brief The identity fields of @p file (only those elements are parsed).
/// @throw IoError naming the file when it cannot be read as DICOM
DicomIdentity readDicomIdentity(const std::filesystem::path& file);

} // namespace voxhap::volume
