// SPDX-License-Identifier: Apache-2.0
/// @file NiftiHeader.cpp
/// @brief niftilib for the header and its transforms, after a check of our
/// own of the fields niftilib would "fix" or complain about on stderr; fuzzed
/// (fuzz/FuzzNiftiHeader.cpp).

#include "volume/io/NiftiHeader.h"

#include "volume/io/ByteSource.h"
#include "core/Errors.h"

#include <nifti2_io.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>

namespace voxhap::volume {

namespace {

struct NiftiFree {
    void operator()(nifti_image* n) const { nifti_image_free(n); }
};

SampleType sampleType(int datatype, const std::string& file)
{
    switch (datatype) {
    case DT_INT8:
        return SampleType::Int8;
    case DT_UINT8:
        return SampleType::UInt8;
    case DT_INT16:
        return SampleType::Int16;
    case DT_UINT16:
        return SampleType::UInt16;
    case DT_INT32:
        return SampleType::Int32;
    case DT_UINT32:
        return SampleType::UInt32;
    case DT_FLOAT32:
        return SampleType::Float32;
    case DT_FLOAT64:
        return SampleType::Float64;
    default:
        break;
    }
    throw IoError(file + ": datatype: code " + std::to_string(datatype) + " is not a supported scalar type");
}

/// niftilib reads a header with a wrong magic as ANALYZE 7.5 (or worse, as
/// NIfTI after "fixing" it): check sizeof_hdr and the magic ourselves.
void checkMagic(const std::filesystem::path& file, const std::string& name)
{
    std::string n = file.filename().string();
    const bool gz = n.size() > 3 && n.compare(n.size() - 3, 3, ".gz") == 0;
    ByteSource src(file, 0, gz);
    unsigned char h[548] = {};
    const std::size_t got = src.read(h, sizeof h);
    std::int32_t size = 0;
    std::memcpy(&size, h, 4);
    const std::int32_t swapped = std::int32_t(__builtin_bswap32(std::uint32_t(size)));
    const bool swap = size != 348 && size != 540;
    const auto i16 = [&](std::size_t at) {
        std::uint16_t v;
        std::memcpy(&v, h + at, 2);
        return std::int16_t(swap ? __builtin_bswap16(v) : v);
    };
    const auto i64 = [&](std::size_t at) {
        std::uint64_t v;
        std::memcpy(&v, h + at, 8);
        return std::int64_t(swap ? __builtin_bswap64(v) : v);
    };
    // dim[] and datatype checked here too: niftilib prints its own "** ERROR"
    // lines on stderr for them, and voxhap reports one line of its own.
    const auto checkDims = [&](std::int64_t ndim, auto dim) {
        if (ndim < 1 || ndim > 7)
            throw IoError(name + ": dim: dim[0] = " + std::to_string(ndim) + " (1 to 7 expected)");
        for (int a = 1; a <= ndim; ++a) {
            if (dim(a) < 1)
                throw IoError(
                    name + ": dim: dim[" + std::to_string(a) + "] = " + std::to_string(dim(a)) + " (must be positive)");
        }
    };
    std::int16_t datatype = 0;
    bool nifti = false;
    if (got >= 348 && (size == 348 || swapped == 348)) {
        const std::string magic(reinterpret_cast<const char*>(h + 344), 4);
        nifti = magic == std::string("n+1\0", 4) || magic == std::string("ni1\0", 4);
        if (nifti) {
            checkDims(i16(40), [&](int a) { return std::int64_t(i16(40 + 2 * std::size_t(a))); });
            datatype = i16(70);
        }
    } else if (got >= 540 && (size == 540 || swapped == 540)) {
        const std::string magic(reinterpret_cast<const char*>(h + 4), 4);
        nifti = magic == std::string("n+2\0", 4) || magic == std::string("ni2\0", 4);
        if (nifti) {
            checkDims(i64(16), [&](int a) { return i64(16 + 8 * std::size_t(a)); });
            datatype = i16(12);
        }
    } else {
        throw IoError(
            name + ": header: sizeof_hdr is neither 348 (NIfTI-1) nor 540 (NIfTI-2), or the file is truncated");
    }
    if (nifti) {
        sampleType(datatype, name); // throws on an unsupported datatype
        return;
    }
    throw IoError(name + ": magic: not n+1/ni1 or n+2/ni2 (ANALYZE 7.5 or a corrupt header)");
}

} // namespace

NiftiHeader readNiftiHeader(const std::filesystem::path& file, std::uint64_t memoryCapBytes)
{
    static std::once_flag quiet;
    std::call_once(quiet, [] { nifti_set_debug_level(0); }); // voxhap reports its own one-line errors
    const std::string name = file.string();
    if (!std::filesystem::is_regular_file(file)) throw IoError(name + ": no such file");
    if (file.extension() != ".hdr") checkMagic(file, name);                         // .hdr/.img pairs: niftilib checks
    std::unique_ptr<nifti_image, NiftiFree> nim(nifti_image_read(name.c_str(), 0)); // header only
    if (!nim)
        throw IoError(name + ": header: not a readable NIfTI file (wrong magic, truncated or inconsistent header)");
    if (nim->nifti_type == NIFTI_FTYPE_ANALYZE) {
        throw IoError(name + ": magic: ANALYZE 7.5, not NIfTI (no reliable orientation); convert it to NIfTI first");
    }
    if (nim->ndim < 1 || nim->ndim > 3) {
        throw IoError(
            name + ": dim: " + std::to_string(nim->ndim) + " dimensions (only 3D volumes are read, not time series)");
    }
    if (nim->nx > (1 << 24) || nim->ny > (1 << 24) || nim->nz > (1 << 24))
        throw IoError(name + ": dim: size out of range");
    NiftiHeader h;
    RasterLayout& layout = h.layout;
    layout.dims = Vec3i(int(nim->nx), int(nim->ny), int(nim->nz));
    checkRasterSize(layout.dims, memoryCapBytes, name, "dim");
    layout.type = sampleType(nim->datatype, name);
    constexpr int kMsbFirst = 2; // niftilib's MSB_FIRST, defined only inside its own sources
    layout.bigEndian = nim->byteorder == kMsbFirst;
    // Spec: a slope of 0 (or not finite) means the values are stored unscaled.
    if (std::isfinite(nim->scl_slope) && nim->scl_slope != 0.0) {
        layout.slope = nim->scl_slope;
        layout.intercept = std::isfinite(nim->scl_inter) ? nim->scl_inter : 0.0;
    }

    // ijk → RAS: the sform if set, else the qform, else voxel sizes only.
    Mat3d linear = Mat3d::Zero();
    Vec3d offset = Vec3d::Zero();
    std::string frame;
    if (nim->sform_code > 0 || nim->qform_code > 0) {
        const nifti_dmat44& m = nim->sform_code > 0 ? nim->sto_xyz : nim->qto_xyz;
        frame = nim->sform_code > 0 ? "sform" : "qform";
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) linear(r, c) = m.m[r][c];
            offset[r] = m.m[r][3];
        }
    } else {
        frame = "pixdim (no orientation in the file)";
        linear = Vec3d(std::abs(nim->dx), std::abs(nim->dy), std::abs(nim->dz)).asDiagonal();
    }
    const Vec3d rasToLps(-1, -1, 1);
    Geometry& g = h.geometry;
    for (int c = 0; c < 3; ++c) {
        const Vec3d axis = linear.col(c).cwiseProduct(rasToLps);
        g.spacing[c] = axis.norm();
        if (!(g.spacing[c] > 0) || !std::isfinite(g.spacing[c])) {
            throw IoError(name + ": " + frame + ": axis " + std::to_string(c) + " has zero or non-finite length");
        }
        g.direction.col(c) = axis / g.spacing[c];
    }
    g.origin = offset.cwiseProduct(rasToLps);
    try {
        makeTransform(g);
    } catch (const ValueError& e) {
        throw IoError(name + ": " + frame + ": " + e.what());
    }

    h.frame = frame;
    h.dataFile = nim->iname ? nim->iname : name;
    h.gzip = nifti_is_gzfile(h.dataFile.string().c_str()) != 0;
    h.dataOffset = std::uint64_t(nim->iname_offset);
    return h;
}

} // namespace voxhap::volume
