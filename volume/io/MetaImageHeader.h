// SPDX-License-Identifier: Apache-2.0
/// @file MetaImageHeader.h
/// @brief The header of a MetaImage file (.mha or .mhd): fields checked, the
/// data file located.
#pragma once

#include "volume/Volume.h"
#include "volume/io/RasterLayout.h"

#include <cstdint>
#include <filesystem>
#include <string_view>

namespace voxhap::volume {

/// @brief The checked header of a MetaImage file.
struct MetaImageHeader {
    RasterLayout layout;
    Geometry geometry;
    bool compressed = false;
    std::filesystem::path dataFile; ///< the file holding the voxels
    std::uint64_t dataOffset = 0;   ///< where they start in it [bytes]
};

/// @brief Parse a header; @p text is the file's first bytes (up to 64 KiB),
/// @p file names it in errors and locates a separate data file.
/// @throw IoError "<file>: <field>: ..."
MetaImageHeader parseMetaImageHeader(std::string_view text, const std::filesystem::path& file);

} // namespace voxhap::volume
