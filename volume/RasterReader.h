// SPDX-License-Identifier: Apache-2.0
/// @file RasterReader.h
/// @brief What the single-file raster readers (NRRD, MetaImage, NIfTI) share:
/// sample types, byte sources (raw, gzip/zlib), the memory cap checked before
/// anything is allocated, and slab-wise conversion into a sparse grid.
#pragma once

#include "volume/Volume.h"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <string>

namespace voxhap::volume {

/// @brief Stored sample types of raster files.
enum class SampleType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };
std::size_t sampleBytes(SampleType t);

/// @brief Choices every raster reader takes.
struct RasterOptions {
    Channel channel = Channel::Hu;  ///< where the values go, unless the file says (voxhap-written NRRD)
    float airHu = -950.0f;          ///< hu below this becomes inactive air [HU]
    float airT1 = 0.0f;             ///< t1 below this becomes inactive [t1 units]
    std::uint64_t memoryCapBytes = std::uint64_t(4) << 30; ///< refuse larger grids before allocating
    std::function<void(double)> progress;                   ///< fraction done, may be empty
};

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

/// @brief The layout of the voxel block.
struct RasterLayout {
    Vec3i dims{0, 0, 0};            ///< samples along i (fastest), j, k
    SampleType type = SampleType::Float32;
    bool bigEndian = false;
    double slope = 1.0, intercept = 0.0; ///< value = slope · stored + intercept
};

/// @brief Refuse, before allocating, dimensions whose float grid could exceed the cap.
/// @throw IoError "<file>: <field>: ... over the memory cap"
void checkRasterSize(const Vec3i& dims, std::uint64_t capBytes, const std::string& file, const std::string& field);

/// @brief Read the voxel block into a sparse float grid slab by slab.
/// @throw IoError naming @p file and the "data" field: truncated data, non-finite values
Volume::GridPtr readRaster(ByteSource& src, const RasterLayout& layout, Channel channel, const RasterOptions& options,
                           const std::string& file);

} // namespace voxhap::volume
