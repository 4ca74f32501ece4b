// SPDX-License-Identifier: Apache-2.0
/// @file MetaImageFile.cpp
/// @brief "Key = Value" header parsing and data location for MetaImage.

#include "volume/io/MetaImageFile.h"

#include "core/BoundedRead.h"
#include "core/Errors.h"

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

namespace voxhap::volume {

namespace {

/// The data file of a .mhd: a regular file in the header's own folder, also
/// once symbolic links are resolved (a link named like a file of the folder
/// may lead anywhere: /etc/passwd, /dev/zero, a FIFO).
void checkMetaImageDataFile(const std::filesystem::path& data, const std::filesystem::path& header)
{
    namespace fs = std::filesystem;
    const std::string name = header.string(), shown = data.filename().string();
    std::error_code ec;
    const fs::file_status st = fs::status(data, ec);
    if (!fs::exists(st)) throw IoError(name + ": ElementDataFile: " + data.string() + " not found");
    const fs::path folder = fs::weakly_canonical(fs::absolute(header).parent_path(), ec);
    const fs::path resolved = fs::weakly_canonical(fs::absolute(data), ec);
    if (ec || resolved.parent_path() != folder) {
        throw IoError(name + ": ElementDataFile: '" + shown + "' leads to " + resolved.string() +
            ", outside the header's own folder");
    }
    if (!fs::is_regular_file(st)) {
        throw IoError(name + ": ElementDataFile: '" + shown + "' is not a regular file (a FIFO, a device or a folder)");
    }
}

} // namespace

Volume loadMetaImage(const std::filesystem::path& file, const RasterOptions& options)
{
    const std::string name = file.string();
    requireRegularFile(file, "MetaImage header"); // a FIFO or a device is refused before it is opened
    std::ifstream in(file, std::ios::binary);
    if (!in) throw IoError(name + ": cannot open");
    std::string text(1 << 16, '\0'); // headers are a few hundred bytes: this bounds a corrupt file
    in.read(text.data(), std::streamsize(text.size()));
    text.resize(std::size_t(in.gcount()));
    const MetaImageHeader h = parseMetaImageHeader(text, file);
    checkRasterSize(h.layout.dims, options.memoryCapBytes, name, "DimSize");
    if (h.dataFile != file) checkMetaImageDataFile(h.dataFile, file);
    ByteSource src(h.dataFile, h.dataOffset, h.compressed);
    Volume v(h.geometry, IndexBox{Vec3i::Zero(), h.layout.dims - Vec3i::Ones()});
    v.setGrid(options.channel, readRaster(src, h.layout, options.channel, options, h.dataFile.string()));
    src.finish(); // the whole compressed stream must check out, not just the bytes the voxels took
    v.metadata().source = file.filename().string();
    return v;
}

} // namespace voxhap::volume
