// SPDX-License-Identifier: Apache-2.0
/// @file VdbFile.h
/// @brief Save and load a Volume as an OpenVDB .vdb file.
///
/// Grids are stored under their channel names ("hu", "t1", "label"); the
/// dense extent and the metadata as file-level "voxhap.*" entries. A round
/// trip reproduces grids, transform and metadata exactly.
#pragma once

#include "volume/Volume.h"

#include <filesystem>

namespace voxhap::volume {

/// @brief Write @p v to @p file. The file appears only when complete: it is
/// written beside the target under a temporary name, then renamed.
/// @throw IoError naming the file
void saveVdb(const Volume& v, const std::filesystem::path& file);

/// @brief Read a .vdb file written by saveVdb, or any .vdb whose grids are
/// named hu, t1 and/or label (other grids are ignored).
/// @throw IoError naming the file and the offending grid or field
Volume loadVdb(const std::filesystem::path& file);

} // namespace voxhap::volume
