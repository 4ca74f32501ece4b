// SPDX-License-Identifier: Apache-2.0
/// @file NiftiHeader.cpp
/// @brief niftilib for the header and its transforms, after a check of our
/// own of the fields niftilib would "fix" or complain about on stderr; fuzzed
/// (fuzz/FuzzNiftiHeader.cpp).

#include "volume/io/NiftiHeader.h"
#include "volume/io/RasterLayout.h"

#include "core/BoundedRead.h"
#include "core/Errors.h"
#include "volume/io/ByteSource.h"

#include <nifti2_io.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

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

std::string niftiNumber(double v)
{
    char text[40];
    std::snprintf(text, sizeof text, "%.9g", v);
    return text;
}

/// What voxhap's own reading of the raw header found, before niftilib.
struct NiftiRawHeader {
    bool nifti = false;      ///< false: ANALYZE 7.5 in a .hdr (niftilib then names it)
    bool singleFile = false; ///< magic n+1 / n+2: header and data in one file
    std::uint64_t voxOffset = 0;
};

/// niftilib reads a header with a wrong magic as ANALYZE 7.5 (or worse, as
/// NIfTI after "fixing" it), replaces an impossible vox_offset by 352 and a
/// non-positive voxel size by 1 mm: check those fields ourselves, from the raw
/// bytes, and refuse what is wrong instead (docs/reference.md "Refused header fields").
NiftiRawHeader checkRawHeader(const std::filesystem::path& file, const std::string& name, bool pair)
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
    const auto u16 = [&](std::size_t at) {
        std::uint16_t v;
        std::memcpy(&v, h + at, 2);
        return swap ? __builtin_bswap16(v) : v;
    };
    const auto i16 = [&](std::size_t at) { return std::int16_t(u16(at)); };
    const auto i64 = [&](std::size_t at) {
        std::uint64_t v;
        std::memcpy(&v, h + at, 8);
        return std::int64_t(swap ? __builtin_bswap64(v) : v);
    };
    const auto f32 = [&](std::size_t at) {
        std::uint32_t v;
        std::memcpy(&v, h + at, 4);
        if (swap) v = __builtin_bswap32(v);
        float f;
        std::memcpy(&f, &v, 4);
        return double(f);
    };
    const auto f64 = [&](std::size_t at) {
        const std::int64_t v = i64(at);
        double d;
        std::memcpy(&d, &v, 8);
        return d;
    };
    // Every field below named as the NIfTI standard names it. dim[] and
    // datatype are checked here too: niftilib prints its own "** ERROR" lines
    // on stderr for them, and voxhap reports one line of its own.
    const auto checkDims = [&](std::int64_t ndim, auto dim, SampleType type) {
        if (ndim < 1 || ndim > 7)
            throw IoError(name + ": dim: dim[0] = " + std::to_string(ndim) + " (1 to 7 expected)");
        std::uint64_t bytes = sampleBytes(type);
        for (int a = 1; a <= ndim; ++a) {
            if (dim(a) < 1)
                throw IoError(
                    name + ": dim: dim[" + std::to_string(a) + "] = " + std::to_string(dim(a)) + " (must be positive)");
            if (__builtin_mul_overflow(bytes, std::uint64_t(dim(a)), &bytes) ||
                bytes > std::uint64_t(std::numeric_limits<std::int64_t>::max())) {
                throw IoError(name + ": dim: the product dim[1] × … × dim[" + std::to_string(a) +
                    "] × bytes per voxel overflows a 64-bit byte count");
            }
        }
    };
    const auto checkPixdim = [&](std::int64_t ndim, auto dim, auto pixdim) {
        for (int a = 1; a <= 3 && a <= ndim; ++a) {
            if (dim(a) > 1 && !(std::isfinite(pixdim(a)) && pixdim(a) > 0)) {
                throw IoError(name + ": pixdim: pixdim[" + std::to_string(a) + "] = " + niftiNumber(pixdim(a)) +
                    " on an axis of " + std::to_string(dim(a)) + " voxels (a positive, finite voxel size expected)");
            }
        }
    };
    const auto checkScaling = [&](double slope, double inter) {
        if (!std::isfinite(slope))
            throw IoError(
                name + ": scl_slope: " + niftiNumber(slope) + " (a finite number, or 0 for unscaled, expected)");
        if (slope != 0.0 && !std::isfinite(inter))
            throw IoError(name + ": scl_inter: " + niftiNumber(inter) + " (a finite number expected)");
    };
    // vox_offset: a whole, non-negative byte count; in a single file at least
    // the header and its 4-byte extension flag (352 or 544); 0 is valid in a
    // .hdr/.img pair. Whether it lies within the data is checked once the
    // data file is known (readNiftiHeader, loadNifti).
    const auto voxOffset = [&](double v, std::uint64_t minimum) -> std::uint64_t {
        if (!std::isfinite(v))
            throw IoError(name + ": vox_offset: " + niftiNumber(v) + " (a finite byte offset expected)");
        if (v < 0) throw IoError(name + ": vox_offset: " + niftiNumber(v) + " is negative");
        if (v != std::floor(v))
            throw IoError(name + ": vox_offset: " + niftiNumber(v) + " is not a whole number of bytes");
        if (v < double(minimum)) {
            throw IoError(name + ": vox_offset: " + niftiNumber(v) + " lies inside the header (at least " +
                std::to_string(minimum) + " in a single-file NIfTI: the header and its 4-byte extension flag)");
        }
        // Beyond 2^62 no file holds it: readNiftiHeader reports it as beyond the end.
        return v >= 4.6e18 ? std::numeric_limits<std::uint64_t>::max() : std::uint64_t(v);
    };
    NiftiRawHeader r;
    if (got >= 348 && (size == 348 || swapped == 348)) {
        const std::string magic(reinterpret_cast<const char*>(h + 344), 4);
        r.singleFile = magic == std::string("n+1\0", 4);
        r.nifti = r.singleFile || magic == std::string("ni1\0", 4);
        if (r.nifti) {
            const auto dim = [&](int a) { return std::int64_t(i16(40 + 2 * std::size_t(a))); };
            const SampleType type = sampleType(i16(70), name);
            checkDims(dim(0), dim, type);
            checkPixdim(dim(0), dim, [&](int a) { return f32(76 + 4 * std::size_t(a)); });
            r.voxOffset = voxOffset(f32(108), r.singleFile ? 352 : 0);
            checkScaling(f32(112), f32(116));
        }
    } else if (got >= 540 && (size == 540 || swapped == 540)) {
        const std::string magic(reinterpret_cast<const char*>(h + 4), 4);
        r.singleFile = magic == std::string("n+2\0", 4);
        r.nifti = r.singleFile || magic == std::string("ni2\0", 4);
        if (r.nifti) {
            const auto dim = [&](int a) { return i64(16 + 8 * std::size_t(a)); };
            const SampleType type = sampleType(i16(12), name);
            checkDims(dim(0), dim, type);
            checkPixdim(dim(0), dim, [&](int a) { return f64(104 + 8 * std::size_t(a)); });
            const std::int64_t offset = i64(168);
            if (offset < 0) throw IoError(name + ": vox_offset: " + std::to_string(offset) + " is negative");
            voxOffset(double(offset), r.singleFile ? 544 : 0);
            r.voxOffset = std::uint64_t(offset); // exact, not through a double
            checkScaling(f64(176), f64(184));
        }
    } else {
        throw IoError(
            name + ": header: sizeof_hdr is neither 348 (NIfTI-1) nor 540 (NIfTI-2), or the file is truncated");
    }
    if (!r.nifti && !pair) throw IoError(name + ": magic: not n+1/ni1 or n+2/ni2 (ANALYZE 7.5 or a corrupt header)");
    if (r.singleFile) {
        // Within the file (the inflated stream of a .nii.gz), before niftilib
        // reads extensions up to vox_offset: at least one byte of data follows.
        std::uint64_t length = got;
        if (!gz) {
            length = std::filesystem::file_size(file);
        } else if (got == sizeof h && r.voxOffset >= length) {
            std::vector<unsigned char> discard(1 << 16);
            for (std::size_t more; length <= r.voxOffset && (more = src.read(discard.data(), discard.size())) > 0;)
                length += more;
        }
        if (r.voxOffset >= length) {
            throw IoError(name + ": vox_offset: " + std::to_string(r.voxOffset) + " is beyond the end of the " +
                (gz ? "decompressed data (" : "file (") + std::to_string(length) + " bytes)");
        }
    }
    return r;
}

} // namespace

namespace {

/// The header's fields, read and checked; for a .nii.gz without verifying the
/// stream they came from (readNiftiHeader does that when they fail).
NiftiHeader readHeaderFields(const std::filesystem::path& file, const std::string& name, std::uint64_t memoryCapBytes)
{
    // A .hdr without a NIfTI magic is ANALYZE 7.5: niftilib recognises it and it is refused below.
    const NiftiRawHeader raw = checkRawHeader(file, name, file.extension() == ".hdr");
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
    // Spec: a slope of 0 means the values are stored unscaled; a non-finite
    // slope or intercept was refused with the raw header.
    if (nim->scl_slope != 0.0) {
        layout.slope = nim->scl_slope;
        layout.intercept = nim->scl_inter;
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
    h.dataOffset = raw.voxOffset; // as the file says, whatever niftilib made of it
    if (!std::filesystem::exists(h.dataFile))
        throw IoError(name + ": data file: " + h.dataFile.string() + " not found (the .img of a .hdr/.img pair)");
    if (!std::filesystem::is_regular_file(h.dataFile)) { // a FIFO would block the open, a device never end
        throw IoError(name + ": data file: " + h.dataFile.filename().string() +
            " is a FIFO, a device or a folder, not a regular file");
    }
    if (!raw.singleFile && !h.gzip) { // a compressed .img: checked as its data is read (loadNifti)
        const std::uint64_t length = std::filesystem::file_size(h.dataFile);
        if (h.dataOffset >= length) {
            throw IoError(name + ": vox_offset: " + std::to_string(h.dataOffset) + " is beyond the end of " +
                h.dataFile.filename().string() + " (" + std::to_string(length) + " bytes)");
        }
    }
    return h;
}

} // namespace

NiftiHeader readNiftiHeader(const std::filesystem::path& file, std::uint64_t memoryCapBytes)
{
    static std::once_flag quiet;
    std::call_once(quiet, [] { nifti_set_debug_level(0); }); // voxhap reports its own one-line errors
    const std::string name = file.string();
    if (!std::filesystem::exists(file)) throw IoError(name + ": no such file");
    requireRegularFile(file, "NIfTI file"); // a FIFO or a device is refused before it is opened
    try {
        return readHeaderFields(file, name, memoryCapBytes);
    } catch (const IoError&) {
        // In a .nii.gz the header is inside the compressed stream: damage to the
        // stream shows first as nonsense header fields. When the stream itself
        // fails its checks, that is the error to report (it throws here);
        // otherwise the header really is wrong.
        if (name.size() > 3 && name.compare(name.size() - 3, 3, ".gz") == 0) {
            ByteSource whole(file, 0, true);
            whole.finish();
        }
        throw;
    }
}

} // namespace voxhap::volume
