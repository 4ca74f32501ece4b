// SPDX-License-Identifier: Apache-2.0
/// @file TransformFile.h
/// @brief A registration's map as an ITK transform file (`.tfm`), written by
/// ITK's own writer, which 3D Slicer loads and applies to the moving image.
/// An affine map is written as one `AffineTransform_double_3_3`, rigid or not.
#pragma once

#include "registration/AffineMap.h"

#include <filesystem>
#include <string>

namespace voxhap::registration {

/// @brief The text ITK writes for @p mrFromCt (fixed → moving points, LPS mm).
std::string itkTransformText(const AffineMap& mrFromCt);

/// @brief Read an ITK transform file holding one affine (or rigid, Euler or
/// versor) transform; the result maps fixed to moving points.
/// @throw IoError naming the file when ITK cannot read it or it holds another kind
AffineMap readItkTransform(const std::filesystem::path& file);

/// @brief The same from text (as a fused volume's metadata keep it).
AffineMap parseItkTransform(const std::string& text, const std::string& where);

} // namespace voxhap::registration
