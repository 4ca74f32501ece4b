// SPDX-License-Identifier: Apache-2.0
/// @file RasterReader.h
/// @brief What the single-file raster readers (NRRD, MetaImage, NIfTI) share:
/// sample types, byte sources (raw, gzip/zlib), the memory cap checked before
/// anything is allocated, and slab-wise conversion into a sparse grid.
#pragma once

#include "core/Progress.h"
#include "volume/Volume.h"
#include "volume/io/ByteSource.h"
#include "volume/io/RasterLayout.h"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <string>

namespace voxhap::volume {

/// @brief Choices every raster reader takes.
struct RasterOptions {
    Channel channel = Channel::Hu; ///< where the values go, unless the file says (voxhap-written NRRD)
    float airHu = -950.0f;         ///< hu below this becomes inactive air [HU]
    float airT1 = 0.0f;            ///< t1 below this becomes inactive [t1 units]
    std::uint64_t memoryCapBytes = std::uint64_t(4) << 30; ///< refuse larger grids before allocating
    Progress progress;                                     ///< fraction done, may be empty
};

/// @brief Read the voxel block into a sparse float grid slab by slab.
/// @throw IoError naming @p file and the "data" field: truncated data, non-finite values
Volume::GridPtr readRaster(ByteSource& src, const RasterLayout& layout, Channel channel, const RasterOptions& options,
    const std::string& file);

} // namespace voxhap::volume
