// SPDX-License-Identifier: Apache-2.0
/// @file FuzzMetaImageCompressed.cpp
/// @brief libFuzzer target: the zlib voxel stream of a .mha (CompressedData)
/// under a fixed header. Refused, or exactly the unmutated file's voxels
/// (FuzzCompressed.h). The seeds also hold gzip-wrapped streams, which
/// MetaImage readers accept.

#include "FuzzCompressed.h"

#include "volume/io/MetaImageFile.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    using namespace voxhap::fuzz;
    static const std::string reference = deflated(compressedSamples(), 15);
    // CompressedDataSize is the unmutated stream's: the header does not follow the mutation.
    static CompressedTarget target(".mha",
        "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\nCompressedData = True\n"
        "CompressedDataSize = " +
            std::to_string(reference.size()) +
            "\nTransformMatrix = 1 0 0 0 1 0 0 0 1\nOffset = -20 -30 10\nElementSpacing = 0.75 0.75 2.5\nDimSize = " +
            std::to_string(kCompressedNx) + " " + std::to_string(kCompressedNy) + " " + std::to_string(kCompressedNz) +
            "\nElementType = MET_SHORT\nElementDataFile = LOCAL\n",
        reference, [](const std::filesystem::path& p) { return voxhap::volume::loadMetaImage(p); });
    return target.run(data, size);
}
