// SPDX-License-Identifier: Apache-2.0
/// @file MetaImageFile.cpp
/// @brief "Key = Value" header parsing and data location for MetaImage.

#include "volume/io/MetaImageFile.h"

#include "core/Errors.h"

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

namespace voxhap::volume {

Volume loadMetaImage(const std::filesystem::path& file, const RasterOptions& options)
{
    const std::string name = file.string();
    std::ifstream in(file, std::ios::binary);
    if (!in) throw IoError(name + ": cannot open");
    std::string text(1 << 16, '\0'); // headers are a few hundred bytes: this bounds a corrupt file
    in.read(text.data(), std::streamsize(text.size()));
    text.resize(std::size_t(in.gcount()));
    const MetaImageHeader h = parseMetaImageHeader(text, file);
    checkRasterSize(h.layout.dims, options.memoryCapBytes, name, "DimSize");
    if (!std::filesystem::is_regular_file(h.dataFile))
        throw IoError(name + ": ElementDataFile: " + h.dataFile.string() + " not found");
    ByteSource src(h.dataFile, h.dataOffset, h.compressed);
    Volume v(h.geometry, IndexBox{Vec3i::Zero(), h.layout.dims - Vec3i::Ones()});
    v.setGrid(options.channel, readRaster(src, h.layout, options.channel, options, h.dataFile.string()));
    src.finish(); // the whole compressed stream must check out, not just the bytes the voxels took
    v.metadata().source = file.filename().string();
    return v;
}

} // namespace voxhap::volume
