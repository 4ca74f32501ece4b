// SPDX-License-Identifier: Apache-2.0
/// @file NiftiFile.cpp
/// @brief NIfTI volumes: the checked header (NiftiHeader), then the voxels
/// through ByteSource.

#include "volume/io/NiftiFile.h"

#include "volume/io/NiftiHeader.h"

#include "core/Errors.h"

#include <algorithm>
#include <vector>

namespace voxhap::volume {

Volume loadNifti(const std::filesystem::path& file, const RasterOptions& options)
{
    const NiftiHeader h = readNiftiHeader(file, options.memoryCapBytes);
    // gzip: vox_offset counts in the inflated stream; a compressed .img of a
    // .hdr/.img pair is checked against its inflated length here.
    ByteSource src(h.dataFile, h.gzip ? 0 : h.dataOffset, h.gzip);
    if (h.gzip) {
        std::vector<char> discard(1 << 16);
        std::uint64_t skipped = 0;
        while (skipped < h.dataOffset) {
            const std::size_t want = std::size_t(std::min<std::uint64_t>(h.dataOffset - skipped, discard.size()));
            const std::size_t got = src.read(discard.data(), want);
            skipped += got;
            if (got < want) {
                throw IoError(file.string() + ": vox_offset: " + std::to_string(h.dataOffset) +
                    " is beyond the end of the decompressed data of " + h.dataFile.filename().string() + " (" +
                    std::to_string(skipped) + " bytes)");
            }
        }
    }
    Volume v(h.geometry, IndexBox{Vec3i::Zero(), h.layout.dims - Vec3i::Ones()});
    v.setGrid(options.channel, readRaster(src, h.layout, options.channel, options, h.dataFile.string()));
    src.finish(); // the whole compressed stream must check out, not just the bytes the voxels took
    v.metadata().source = file.filename().string();
    v.metadata().extra["nifti_transform"] = h.frame;
    return v;
}

} // namespace voxhap::volume
