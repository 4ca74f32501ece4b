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
    /// Concatenated gzip members are one stream (RFC 1952 §2.2).
    /// @throw IoError naming the file on corrupt compressed data
    std::size_t read(void* out, std::size_t n);

    /// @brief Compressed data: inflate the rest of the stream (discarding it)
    /// and require that it ends with verified trailers — the CRC-32 and length
    /// of every gzip member, the Adler-32 of a zlib stream — and that no byte
    /// follows the last member. A reader that stops once it has its voxels
    /// would otherwise accept bit flips and a cut or flipped trailer.
    /// Raw data: nothing to check.
    /// @throw IoError naming the file and the byte offset of the problem
    void finish();

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace voxhap::volume
