// SPDX-License-Identifier: Apache-2.0
/// @file RasterReader.cpp
/// @brief Byte sources, sample conversion and slab-wise sparse building.

#include "volume/RasterReader.h"

#include "volume/Errors.h"
#include "volume/SparseSlabs.h"

#include <zlib.h>

#include <cstring>
#include <sstream>
#include <vector>

namespace voxhap::volume {

std::size_t sampleBytes(SampleType t)
{
    switch (t) {
    case SampleType::Int8:
    case SampleType::UInt8: return 1;
    case SampleType::Int16:
    case SampleType::UInt16: return 2;
    case SampleType::Int32:
    case SampleType::UInt32:
    case SampleType::Float32: return 4;
    case SampleType::Float64: return 8;
    }
    return 1;
}

struct ByteSource::Impl {
    std::string name;
    std::ifstream in;
    bool compressed = false;
    z_stream z{};
    bool zOpen = false, zEnd = false;
    std::vector<char> buf;
};

ByteSource::ByteSource(const std::filesystem::path& file, std::uint64_t offset, bool compressed, std::uint64_t skip)
    : mImpl(std::make_unique<Impl>())
{
    mImpl->name = file.string();
    mImpl->in.open(file, std::ios::binary);
    if (!mImpl->in) throw IoError(mImpl->name + ": cannot open");
    mImpl->in.seekg(std::streamoff(offset));
    mImpl->compressed = compressed;
    if (compressed) {
        // windowBits 15 + 32: accept a gzip or a zlib header (NRRD and NIfTI
        // use gzip, MetaImage zlib).
        if (inflateInit2(&mImpl->z, 15 + 32) != Z_OK) throw IoError(mImpl->name + ": zlib initialisation failed");
        mImpl->zOpen = true;
        mImpl->buf.resize(1 << 16);
    }
    std::vector<char> discard(1 << 12);
    while (skip > 0) {
        const std::size_t n = std::size_t(std::min<std::uint64_t>(skip, discard.size()));
        if (read(discard.data(), n) != n) throw IoError(mImpl->name + ": data: the file ends before its data starts (truncated file)");
        skip -= n;
    }
}

ByteSource::~ByteSource()
{
    if (mImpl->zOpen) inflateEnd(&mImpl->z);
}

std::size_t ByteSource::read(void* out, std::size_t n)
{
    Impl& m = *mImpl;
    if (!m.compressed) {
        m.in.read(static_cast<char*>(out), std::streamsize(n));
        return std::size_t(m.in.gcount());
    }
    m.z.next_out = static_cast<Bytef*>(out);
    m.z.avail_out = uInt(n);
    while (m.z.avail_out > 0 && !m.zEnd) {
        if (m.z.avail_in == 0) {
            m.in.read(m.buf.data(), std::streamsize(m.buf.size()));
            const auto got = m.in.gcount();
            if (got <= 0) break; // compressed stream ends early: the caller sees a short read
            m.z.next_in = reinterpret_cast<Bytef*>(m.buf.data());
            m.z.avail_in = uInt(got);
        }
        const int rc = inflate(&m.z, Z_NO_FLUSH);
        if (rc == Z_STREAM_END) m.zEnd = true;
        else if (rc != Z_OK && rc != Z_BUF_ERROR) {
            throw IoError(m.name + ": data: corrupt compressed data (" + std::string(m.z.msg ? m.z.msg : "zlib error") + ")");
        }
    }
    return n - m.z.avail_out;
}

void checkRasterSize(const Vec3i& dims, std::uint64_t capBytes, const std::string& file, const std::string& field)
{
    for (int a = 0; a < 3; ++a) {
        if (dims[a] < 1) throw IoError(file + ": " + field + ": size " + std::to_string(dims[a]) + " along axis " + std::to_string(a) + " must be positive");
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

namespace {

template <typename T>
void convert(const unsigned char* raw, std::size_t count, bool swap, double slope, double intercept, float* out)
{
    for (std::size_t n = 0; n < count; ++n) {
        unsigned char b[sizeof(T)];
        std::memcpy(b, raw + n * sizeof(T), sizeof(T));
        if (swap) {
            for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
        }
        T v;
        std::memcpy(&v, b, sizeof(T));
        out[n] = (slope == 1.0 && intercept == 0.0) ? float(v) : float(slope * double(v) + intercept);
    }
}

} // namespace

Volume::GridPtr readRaster(ByteSource& src, const RasterLayout& l, Channel channel, const RasterOptions& o, const std::string& file)
{
    if (channel == Channel::Label) throw IoError(file + ": reading a label volume from this format is not supported");
    const float background = channel == Channel::Hu ? kAirHu : kAirT1;
    const float air = channel == Channel::Hu ? o.airHu : o.airT1;
    const std::size_t plane = std::size_t(l.dims.x()) * std::size_t(l.dims.y());
    const std::size_t bytesPerSample = sampleBytes(l.type);
    const bool swap = l.bigEndian && bytesPerSample > 1; // hosts are little-endian (static_assert in NrrdFile.cpp)
    SparseSlabs sparse(background, air);
    std::vector<unsigned char> raw(plane * SparseSlabs::kSlabSlices * bytesPerSample);
    std::vector<float> slab(plane * SparseSlabs::kSlabSlices);
    const std::uint64_t total = std::uint64_t(plane) * std::uint64_t(l.dims.z()) * bytesPerSample;
    std::uint64_t done = 0;
    for (int k0 = 0; k0 < l.dims.z(); k0 += SparseSlabs::kSlabSlices) {
        const int n = std::min(SparseSlabs::kSlabSlices, l.dims.z() - k0);
        const std::size_t want = plane * std::size_t(n) * bytesPerSample;
        const std::size_t got = src.read(raw.data(), want);
        done += got;
        if (got < want) {
            throw IoError(file + ": data: " + std::to_string(done) + " bytes, expected " + std::to_string(total) + " (truncated file)");
        }
        const std::size_t count = plane * std::size_t(n);
        switch (l.type) {
        case SampleType::Int8: convert<std::int8_t>(raw.data(), count, swap, l.slope, l.intercept, slab.data()); break;
        case SampleType::UInt8: convert<std::uint8_t>(raw.data(), count, swap, l.slope, l.intercept, slab.data()); break;
        case SampleType::Int16: convert<std::int16_t>(raw.data(), count, swap, l.slope, l.intercept, slab.data()); break;
        case SampleType::UInt16: convert<std::uint16_t>(raw.data(), count, swap, l.slope, l.intercept, slab.data()); break;
        case SampleType::Int32: convert<std::int32_t>(raw.data(), count, swap, l.slope, l.intercept, slab.data()); break;
        case SampleType::UInt32: convert<std::uint32_t>(raw.data(), count, swap, l.slope, l.intercept, slab.data()); break;
        case SampleType::Float32: convert<float>(raw.data(), count, swap, l.slope, l.intercept, slab.data()); break;
        case SampleType::Float64: convert<double>(raw.data(), count, swap, l.slope, l.intercept, slab.data()); break;
        }
        try {
            sparse.addSlab(slab.data(), l.dims.x(), l.dims.y(), k0, n);
        } catch (const ValueError& e) {
            throw IoError(file + ": data: " + e.what());
        }
        if (o.progress) o.progress(double(k0 + n) / l.dims.z());
    }
    return sparse.finish();
}

} // namespace voxhap::volume
