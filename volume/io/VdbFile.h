// SPDX-License-Identifier: Apache-2.0
/// @file VdbFile.h
/// @brief Save and load a Volume as an OpenVDB .vdb file.
///
/// Grids are stored under their channel names ("hu", "t1", "label"); the
/// dense extent and the metadata as file-level "voxhap.*" entries. A round
/// trip reproduces grids, transform and metadata exactly.
#pragma once

#include "volume/Volume.h"

#include <cstdint>
#include <filesystem>

namespace voxhap::volume {

/// @brief Write @p v to @p file. The file appears only when complete: it is
/// written beside the target under a temporary name, then renamed.
/// @throw IoError naming the file
void saveVdb(const Volume& v, const std::filesystem::path& file);

/// @brief Read a .vdb file written by saveVdb, or any .vdb whose grids are
/// named hu, t1 and/or label (other grids are ignored: only their names are read).
///
/// Before OpenVDB reads anything, the whole container is walked over a
/// read-only mapping of the file: header, file and grid metadata (every
/// count, name, type and value length), grid descriptors and their offsets,
/// transforms, and the tree of every grid voxhap reads (root tile and child
/// counts, node masks, per-node compression, zlib and Blosc chunk sizes,
/// half-float storage, delayed-load metadata). Each length must fit in the
/// bytes that remain, each offset inside the file, and the trees' memory
/// (from their node counts) under @p memoryCapBytes; so a hostile length
/// is refused instead of driving an allocation.
/// @throw IoError naming the file, and for a damaged container the field and
///        its byte offset
Volume loadVdb(const std::filesystem::path& file, std::uint64_t memoryCapBytes = std::uint64_t(4) << 30);

} // namespace voxhap::volume
