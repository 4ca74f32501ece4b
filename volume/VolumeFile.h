// SPDX-License-Identifier: Apache-2.0
/// @file VolumeFile.h
/// @brief Load or save a Volume whatever the format: the one entry point the
/// command line uses. The format comes from the path: a directory or a file
/// with the DICOM magic is DICOM, otherwise the extension decides.
#pragma once

#include "volume/DicomSeries.h"
#include "volume/RasterReader.h"
#include "volume/Volume.h"

#include <filesystem>
#include <string>

namespace voxhap::volume {

enum class VolumeFormat { Dicom, Vdb, Nrrd, Nifti, MetaImage, Unknown };

/// @brief The format of @p path, from its kind, magic and extension.
VolumeFormat formatOf(const std::filesystem::path& path);
std::string formatName(VolumeFormat f);

/// @brief Options of the readers. The air thresholds, memory cap and
/// progress in `dicom` apply to every format.
struct LoadOptions {
    DicomOptions dicom;
    /// Formats that do not say what they hold (NRRD, MetaImage, NIfTI): hu or t1.
    Channel channel = Channel::Hu;
};

/// @brief The raster-reader options that @p o implies.
RasterOptions rasterOptions(const LoadOptions& o);

/// @brief Load @p path. @p report is filled for DICOM inputs.
/// @throw IoError naming the file and the field; for an unknown format too
Volume loadVolume(const std::filesystem::path& path, const LoadOptions& options = {}, DicomLoadReport* report = nullptr);

/// @brief Save @p v to a .vdb (every grid) or .nrrd (hu, else t1, else label).
/// @throw IoError naming the file
void saveVolume(const Volume& v, const std::filesystem::path& file);

} // namespace voxhap::volume
