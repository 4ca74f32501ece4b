// SPDX-License-Identifier: Apache-2.0
/// @file BoundedRead.h
/// @brief The one way voxhap reads a text input whole (scenes, tissue tables,
/// label mappings, markups, insertion scripts): from a regular file only (a
/// FIFO, a device such as /dev/zero or a directory is refused before it is
/// opened for reading, so nothing waits on a writer), and never more than a
/// size limit (16 MiB by default), so that no input can grow without bound.
#pragma once

#include "core/Errors.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace voxhap {

/// @brief The size limit of every JSON and text input [bytes]: 16 MiB, far above
/// any real scene, table or markups file.
inline constexpr std::uint64_t kTextInputLimitBytes = std::uint64_t(16) << 20;

/// @brief Read the whole of @p file, a regular file of at most @p limitBytes.
/// @param what names the input in errors ("scene", "tissue table", ...)
/// @throw IoError "<file>: cannot open the <what> (<why>)" when it is missing or
///        unreadable, "<file>: file type: ... not a regular file ..." for a FIFO,
///        a device, a socket or a directory, and "<file>: size: ... beyond the
///        16 MiB limit ..." when it is larger than the limit; one line each
std::string readBoundedFile(
    const std::filesystem::path& file, std::string_view what, std::uint64_t limitBytes = kTextInputLimitBytes);

/// @brief Refuse @p path unless it is a regular file (or, with @p allowDirectory,
/// a directory): checked from the path alone, without opening it, so that a
/// FIFO with no writer or a device such as /dev/zero is refused at once. A
/// missing path passes (the caller reports it as it always has).
/// @param what names the input in errors ("volume", "scene file", ...)
/// @throw IoError "<path>: file type: a FIFO, not a regular file; ..."
void requireRegularFile(const std::filesystem::path& path, std::string_view what, bool allowDirectory = false);

/// @brief Parse @p text as JSON; every nlohmann::json exception (a syntax error,
/// a number beyond double such as 1e99999, invalid UTF-8) becomes one line.
/// @throw ValueError "<origin>: not valid JSON (<why>)"
nlohmann::json parseJsonText(std::string_view text, const std::string& origin);

/// @brief readBoundedFile() then parseJsonText(), the origin being the file's name.
/// @throw IoError or ValueError as those two
nlohmann::json readJsonFile(
    const std::filesystem::path& file, std::string_view what, std::uint64_t limitBytes = kTextInputLimitBytes);

} // namespace voxhap
