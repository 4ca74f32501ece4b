// SPDX-License-Identifier: Apache-2.0
/// @file RasterReader.cpp
/// @brief Byte sources, sample conversion and slab-wise sparse building.

#include "volume/io/RasterReader.h"

#include "core/Errors.h"
#include "volume/detail/SparseSlabs.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <vector>

namespace voxhap::volume {

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

Volume::GridPtr readRaster(
    ByteSource& src, const RasterLayout& l, Channel channel, const RasterOptions& o, const std::string& file)
{
    if (channel == Channel::Label) throw IoError(file + ": reading a label volume from this format is not supported");
    const float background = channel == Channel::Hu ? kAirHu : kAirT1;
    // MR (t1, intensity): zero and below is background, for magnitude images
    // have no tissue there (a grid saved by voxhap stores its air as 0).
    const float air = channel == Channel::Hu ? o.airHu : std::nextafter(o.airT1, std::numeric_limits<float>::max());
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
            throw IoError(file + ": data: " + std::to_string(done) + " bytes, expected " + std::to_string(total) +
                " (truncated file)");
        }
        const std::size_t count = plane * std::size_t(n);
        switch (l.type) {
        case SampleType::Int8:
            convert<std::int8_t>(raw.data(), count, swap, l.slope, l.intercept, slab.data());
            break;
        case SampleType::UInt8:
            convert<std::uint8_t>(raw.data(), count, swap, l.slope, l.intercept, slab.data());
            break;
        case SampleType::Int16:
            convert<std::int16_t>(raw.data(), count, swap, l.slope, l.intercept, slab.data());
            break;
        case SampleType::UInt16:
            convert<std::uint16_t>(raw.data(), count, swap, l.slope, l.intercept, slab.data());
            break;
        case SampleType::Int32:
            convert<std::int32_t>(raw.data(), count, swap, l.slope, l.intercept, slab.data());
            break;
        case SampleType::UInt32:
            convert<std::uint32_t>(raw.data(), count, swap, l.slope, l.intercept, slab.data());
            break;
        case SampleType::Float32:
            convert<float>(raw.data(), count, swap, l.slope, l.intercept, slab.data());
            break;
        case SampleType::Float64:
            convert<double>(raw.data(), count, swap, l.slope, l.intercept, slab.data());
            break;
        }
        try {
            sparse.addSlab(slab.data(), l.dims.x(), l.dims.y(), k0, n);
        } catch (const ValueError& e) {
            throw IoError(file + ": data: " + e.what());
        }
        if (o.progress) o.progress(double(k0 + n) / l.dims.z(), {});
    }
    return sparse.finish();
}

} // namespace voxhap::volume
