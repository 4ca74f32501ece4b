// SPDX-License-Identifier: Apache-2.0
/// @file NrrdHeader.h
/// @brief The header of an attached-header .nrrd file: fields checked, space
/// converted to LPS.
#pragma once

#include "volume/Volume.h"
#include "volume/io/RasterLayout.h"

#include <cstddef>
#include <map>
#include <string>
#include <string_view>

namespace voxhap::volume {

/// @brief The fields of a NRRD header that voxhap uses, checked.
struct NrrdHeader {
    RasterLayout layout;
    bool gzip = false;
    Geometry geometry;                            ///< LPS, converted from the file's space
    std::map<std::string, std::string> keyValues; ///< "key:=value" lines
    std::size_t dataOffset = 0;                   ///< bytes from the start of the file to the data
};

/// @brief Parse the header at the start of @p text (the file's first bytes,
/// up to and including the blank line that ends the header).
/// @throw IoError "<file>: <field>: ..." on a wrong magic, a missing or
///        malformed field, or an unsupported feature (detached data, skips)
NrrdHeader parseNrrdHeader(std::string_view text, const std::string& file);

} // namespace voxhap::volume
