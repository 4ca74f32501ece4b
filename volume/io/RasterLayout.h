// SPDX-License-Identifier: Apache-2.0
/// @file RasterLayout.h
/// @brief How a raster file stores its voxel block (sample type, byte order,
/// rescale), and the memory cap checked before anything is allocated.
///
/// Apart from RasterReader so that the header parsers, which only fill these
/// fields, build without the grid code (the fuzz targets compile them alone).
#pragma once

#include "core/Math.h"

#include <cstddef>
#include <cstdint>
#include <string>

namespace voxhap::volume {

/// @brief Stored sample types of raster files.
enum class SampleType {
    Int8,
    UInt8,
    Int16,
    UInt16,
    Int32,
    UInt32,
    Float32,
    Float64
};
std::size_t sampleBytes(SampleType t);

/// @brief The layout of the voxel block.
struct RasterLayout {
    Vec3i dims{0, 0, 0}; ///< samples along i (fastest), j, k
    SampleType type = SampleType::Float32;
    bool bigEndian = false;
    double slope = 1.0, intercept = 0.0; ///< value = slope · stored + intercept
};

/// @brief Refuse, before allocating, dimensions whose float grid could exceed the cap.
/// @throw IoError "<file>: <field>: ... over the memory cap"
void checkRasterSize(const Vec3i& dims, std::uint64_t capBytes, const std::string& file, const std::string& field);

} // namespace voxhap::volume
