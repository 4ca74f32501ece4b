// SPDX-License-Identifier: Apache-2.0
/// @file ImageFile.h
/// @brief PNG files through OpenImageIO: written atomically (complete or not
/// at all), read back for the contact sheet and the tests.
#pragma once

#include "render/raster/Image.h"

#include <filesystem>

namespace voxhap::render {

/// @brief Write @p img as an 8-bit RGB PNG.
/// @throw IoError "<file>: cannot write (<why>)"; no partial file is left behind
void writePng(const Image& img, const std::filesystem::path& file);

/// @brief Read an image file (any format OpenImageIO knows) as 8-bit RGB;
/// grey is expanded, alpha dropped. @throw IoError naming the file
Image readImage(const std::filesystem::path& file);

} // namespace voxhap::render
