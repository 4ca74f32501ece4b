// SPDX-License-Identifier: Apache-2.0
/// @file AtomicFile.h
/// @brief Outputs appear complete or not at all: each is written under a
/// temporary name beside the target, then renamed over it; on failure the
/// temporary is removed and the error names the file.
#pragma once

#include <filesystem>
#include <functional>
#include <ostream>

namespace voxhap {

/// @brief Call @p write with a temporary path beside @p file, then rename it to @p file.
/// @throw IoError "<file>: cannot write (<why>)" when @p write throws or the rename fails
void writeAtomically(const std::filesystem::path& file, const std::function<void(const std::filesystem::path&)>& write);

/// @brief writeAtomically() for a stream: @p fill writes the content (binary mode).
/// @throw IoError as above, also when the stream fails (disk full)
void writeStreamAtomically(const std::filesystem::path& file, const std::function<void(std::ostream&)>& fill);

} // namespace voxhap
