// SPDX-License-Identifier: Apache-2.0
/// @file NiftiFile.h
/// @brief Read NIfTI-1 and NIfTI-2 volumes (.nii, .nii.gz, .hdr/.img): the
/// header through Debian's niftilib (qform/sform handling), the voxels
/// streamed slab by slab; RAS world coordinates become LPS once, here.
#pragma once

#include "volume/Volume.h"
#include "volume/io/RasterReader.h"

#include <filesystem>

namespace voxhap::volume {

/// @brief Read a 3D NIfTI volume into @p options.channel (hu by default).
/// The sform is used when its code is set, else the qform, else the voxel
/// sizes alone (no orientation in the file). ANALYZE 7.5 files are refused.
/// @throw IoError naming the file and the field
Volume loadNifti(const std::filesystem::path& file, const RasterOptions& options = {});

} // namespace voxhap::volume
