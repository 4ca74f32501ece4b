// SPDX-License-Identifier: Apache-2.0
/// @file NiftiHeader.h
/// @brief The header of a NIfTI-1/2 file (.nii, .nii.gz, .hdr/.img): layout,
/// geometry in LPS (sform, else qform, else pixdim) and where the data is.
#pragma once

#include "volume/Volume.h"
#include "volume/io/RasterLayout.h"

#include <cstdint>
#include <filesystem>
#include <string>

namespace voxhap::volume {

/// @brief The checked header of a NIfTI file.
struct NiftiHeader {
    RasterLayout layout;
    Geometry geometry;              ///< LPS: RAS from the file with x and y negated
    std::string frame;              ///< "sform", "qform" or the pixdim fallback
    std::filesystem::path dataFile; ///< the .nii itself, or the .img of a pair
    bool gzip = false;
    std::uint64_t dataOffset = 0; ///< where the voxels start in the (inflated) data file [bytes]
};

/// @brief Read and check @p file's header; refuse grids over @p memoryCapBytes.
/// @throw IoError "<file>: <field>: ..." on a wrong magic, a truncated or
///        inconsistent header, an unsupported type or a degenerate transform
NiftiHeader readNiftiHeader(const std::filesystem::path& file, std::uint64_t memoryCapBytes);

} // namespace voxhap::volume
