// SPDX-License-Identifier: Apache-2.0
/// @file RasterLayout.cpp
/// @brief Sample sizes and the memory cap of raster files.

#include "volume/io/RasterLayout.h"

#include "core/Errors.h"

#include <sstream>

namespace voxhap::volume {

std::size_t sampleBytes(SampleType t)
{
    switch (t) {
    case SampleType::Int8:
    case SampleType::UInt8:
        return 1;
    case SampleType::Int16:
    case SampleType::UInt16:
        return 2;
    case SampleType::Int32:
    case SampleType::UInt32:
    case SampleType::Float32:
        return 4;
    case SampleType::Float64:
        return 8;
    }
    return 1;
}

void checkRasterSize(const Vec3i& dims, std::uint64_t capBytes, const std::string& file, const std::string& field)
{
    for (int a = 0; a < 3; ++a) {
        if (dims[a] < 1)
            throw IoError(file + ": " + field + ": size " + std::to_string(dims[a]) + " along axis " +
                std::to_string(a) + " must be positive");
    }
    // Worst case: every voxel active in a float grid.
    const double bytes = double(dims.x()) * double(dims.y()) * double(dims.z()) * sizeof(float);
    if (bytes > double(capBytes)) {
        std::ostringstream os;
        os.precision(1);
        os << std::fixed << file << ": " << field << ": " << dims.x() << "×" << dims.y() << "×" << dims.z()
           << " voxels may need " << bytes / double(1 << 20) << " MiB, over the memory cap of "
           << double(capBytes) / double(1 << 20) << " MiB";
        throw IoError(os.str());
    }
}

} // namespace voxhap::volume
