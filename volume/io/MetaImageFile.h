// SPDX-License-Identifier: Apache-2.0
/// @file MetaImageFile.h
/// @brief Read MetaImage volumes (.mha with the data inline, .mhd with a
/// separate data file): DimSize, ElementSpacing, Offset and TransformMatrix
/// (direction of each index axis, ITK's layout) in LPS, raw or zlib data.
///
/// Hand-parsed: the only maintained MetaIO readers are inside ITK and VTK,
/// which the volume library must not depend on.
#pragma once

#include "volume/Volume.h"
#include "volume/io/MetaImageHeader.h"
#include "volume/io/RasterReader.h"

#include <filesystem>
#include <string_view>

namespace voxhap::volume {

/// @brief Read a .mha or .mhd volume into @p options.channel.
/// @throw IoError naming the file and the field
Volume loadMetaImage(const std::filesystem::path& file, const RasterOptions& options = {});

} // namespace voxhap::volume
