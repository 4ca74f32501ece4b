// SPDX-License-Identifier: Apache-2.0
/// @file NiftiFile.cpp
/// @brief NIfTI volumes: the checked header (NiftiHeader), then the voxels
/// through ByteSource.

#include "volume/io/NiftiFile.h"

#include "volume/io/NiftiHeader.h"

namespace voxhap::volume {

Volume loadNifti(const std::filesystem::path& file, const RasterOptions& options)
{
    const NiftiHeader h = readNiftiHeader(file, options.memoryCapBytes);
    // gzip: niftilib's offset counts in the inflated stream.
    ByteSource src(h.dataFile, h.gzip ? 0 : h.dataOffset, h.gzip, h.gzip ? h.dataOffset : 0);
    Volume v(h.geometry, IndexBox{Vec3i::Zero(), h.layout.dims - Vec3i::Ones()});
    v.setGrid(options.channel, readRaster(src, h.layout, options.channel, options, h.dataFile.string()));
    src.finish(); // the whole compressed stream must check out, not just the bytes the voxels took
    v.metadata().source = file.filename().string();
    v.metadata().extra["nifti_transform"] = h.frame;
    return v;
}

} // namespace voxhap::volume
