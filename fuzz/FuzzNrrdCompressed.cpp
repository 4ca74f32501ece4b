// SPDX-License-Identifier: Apache-2.0
/// @file FuzzNrrdCompressed.cpp
/// @brief libFuzzer target: the gzip voxel stream of a .nrrd under a fixed
/// header. Refused, or exactly the unmutated file's voxels (FuzzCompressed.h).

#include "FuzzCompressed.h"

#include "volume/io/NrrdFile.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    using namespace voxhap::fuzz;
    static CompressedTarget target(".nrrd",
        "NRRD0004\ntype: short\ndimension: 3\nspace: left-posterior-superior\nsizes: " + std::to_string(kCompressedNx) +
            " " + std::to_string(kCompressedNy) + " " + std::to_string(kCompressedNz) +
            "\nspace directions: (0.75,0,0) (0,0.75,0) (0,0,2.5)\nkinds: domain domain domain\nendian: little\n"
            "encoding: gzip\nspace origin: (-20,-30,10)\n\n",
        deflated(compressedSamples(), 15 + 16),
        [](const std::filesystem::path& p) { return voxhap::volume::loadNrrd(p); });
    return target.run(data, size);
}
