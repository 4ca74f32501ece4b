// SPDX-License-Identifier: Apache-2.0
/// @file NrrdFile.h
/// @brief .nrrd files: write one channel of a Volume so that 3D Slicer opens
/// it in the right place (space left-posterior-superior, space directions =
/// direction × spacing, space origin = centre of the first voxel), and read
/// attached-header NRRD volumes (raw or gzip; LPS, RAS or LAS space).
#pragma once

#include "volume/Volume.h"
#include "volume/io/NrrdHeader.h"
#include "volume/io/RasterReader.h"

#include <filesystem>
#include <map>
#include <string>
#include <string_view>

namespace voxhap::volume {

/// @brief How the voxel block of a .nrrd file is stored.
enum class NrrdEncoding {
    Raw,  ///< little-endian binary, no compression
    Gzip, ///< gzip stream (Slicer's default for .nrrd)
};

/// @brief Which keys of voxhap's own a written .nrrd carries.
enum class NrrdKeys {
    Voxhap, ///< voxhap_channel, voxhap_units, ...: read back as the same channel
    Plain,  ///< none: the file reads as a scanner's export would, its modality and
            ///< weighting from a sidecar or the data (the phantom scans use it)
};

/// @brief Write channel @p c of @p v over its dense extent; inactive voxels
/// take the grid's background (air). The file appears only when complete.
/// @throw IoError naming the file; ValueError if the channel is absent
void saveNrrd(const Volume& v, Channel c, const std::filesystem::path& file, NrrdEncoding encoding = NrrdEncoding::Gzip,
    NrrdKeys keys = NrrdKeys::Voxhap);

/// @brief Read a .nrrd volume; the channel comes from the voxhap_channel
/// key (files voxhap wrote) or else from @p options.
/// @throw IoError naming the file and the field
Volume loadNrrd(const std::filesystem::path& file, const RasterOptions& options = {});

} // namespace voxhap::volume
