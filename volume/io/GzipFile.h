// SPDX-License-Identifier: Apache-2.0
/// @file GzipFile.h
/// @brief DICOM files stored gzip-compressed (.dcm.gz, as some archives
/// export them), inflated with every byte verified, into a private folder.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace voxhap::volume {

/// @brief A folder of its own under the system's temporary directory
/// (mkdtemp, mode 0700), removed with everything in it on destruction.
class TemporaryFolder {
public:
    /// @param prefix the start of the folder's name
    /// @throw IoError when it cannot be created
    explicit TemporaryFolder(const std::string& prefix);
    ~TemporaryFolder();
    TemporaryFolder(const TemporaryFolder&) = delete;
    TemporaryFolder& operator=(const TemporaryFolder&) = delete;
    const std::filesystem::path& path() const { return mPath; }

private:
    std::filesystem::path mPath;
};

/// @brief True if @p file starts with the gzip magic (1F 8B, RFC 1952 §2.3.1).
bool isGzipFile(const std::filesystem::path& file);

/// @brief Inflate gzip file @p in to @p out if it holds a DICOM Part 10 file.
///
/// The whole stream is verified as ByteSource::finish() does: every member's
/// CRC-32 and length, concatenated members decoded, any other byte after the
/// last member refused. A damaged stream is refused, never written as if
/// complete (the partial output is removed).
/// @param capBytes refuse inflated data longer than this (a gzip bomb) [bytes]
/// @return false when the inflated data is not DICOM (no DICM preamble): nothing is written
/// @throw IoError naming @p in and the offset of the problem
bool inflateDicomGzip(const std::filesystem::path& in, const std::filesystem::path& out, std::uint64_t capBytes);

} // namespace voxhap::volume
