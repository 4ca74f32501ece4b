// SPDX-License-Identifier: Apache-2.0
/// @file ByteSource.h
/// @brief The bytes of a file from an offset, inflated on the fly if gzip or
/// zlib compressed: how every raster reader streams its voxel block.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>

namespace voxhap::volume {

/// @brief A stream of bytes: a file from an offset, optionally inflated.
class ByteSource {
public:
    /// @param offset     where the (possibly compressed) data starts in the file [bytes]
    /// @param compressed inflate gzip or zlib data (detected from its header)
    /// @param skip       bytes to discard from the start of the (inflated) stream,
    ///                   e.g. a NIfTI header inside a .nii.gz
    ByteSource(const std::filesystem::path& file, std::uint64_t offset, bool compressed, std::uint64_t skip = 0);
    ~ByteSource();
    ByteSource(const ByteSource&) = delete;
    ByteSource& operator=(const ByteSource&) = delete;
    /// @brief Read up to @p n bytes; fewer only at the end of the data.
    /// @throw IoError naming the file on corrupt compressed data
    std::size_t read(void* out, std::size_t n);

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace voxhap::volume
