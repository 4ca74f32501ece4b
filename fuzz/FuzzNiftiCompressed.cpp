// SPDX-License-Identifier: Apache-2.0
/// @file FuzzNiftiCompressed.cpp
/// @brief libFuzzer target: a whole .nii.gz, whose NIfTI header lies inside
/// the gzip stream (the CRC-32 covers it too). Refused, or exactly the
/// unmutated file's voxels (FuzzCompressed.h).

#include "FuzzCompressed.h"

#include "volume/io/NiftiFile.h"

#include <nifti1.h>

#include <cstring>

namespace {

/// A single-file NIfTI-1 of the shared samples: 348-byte header, 4 bytes of
/// empty extension flag, samples; the fields compressed_seeds.py writes.
std::string niftiFile()
{
    using namespace voxhap::fuzz;
    nifti_1_header h;
    std::memset(&h, 0, sizeof h);
    h.sizeof_hdr = 348;
    h.dim[0] = 3, h.dim[1] = kCompressedNx, h.dim[2] = kCompressedNy, h.dim[3] = kCompressedNz;
    for (int a = 4; a < 8; ++a) h.dim[a] = 1;
    h.datatype = DT_INT16;
    h.bitpix = 16;
    h.pixdim[0] = 1, h.pixdim[1] = 0.75f, h.pixdim[2] = 0.75f, h.pixdim[3] = 2.5f;
    h.vox_offset = 352;
    h.xyzt_units = NIFTI_UNITS_MM;
    h.sform_code = NIFTI_XFORM_SCANNER_ANAT;
    h.srow_x[0] = -0.75f, h.srow_x[3] = 20;
    h.srow_y[1] = -0.75f, h.srow_y[3] = 30;
    h.srow_z[2] = 2.5f, h.srow_z[3] = 10;
    std::memcpy(h.magic, "n+1", 4);
    return std::string(reinterpret_cast<const char*>(&h), sizeof h) + std::string(4, '\0') + compressedSamples();
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    using namespace voxhap::fuzz;
    static CompressedTarget target(".nii.gz", "", deflated(niftiFile(), 15 + 16),
        [](const std::filesystem::path& p) { return voxhap::volume::loadNifti(p); });
    return target.run(data, size);
}
