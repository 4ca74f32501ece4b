// SPDX-License-Identifier: Apache-2.0
/// @file FuzzCompressed.h
/// @brief What the content-comparing targets for compressed voxel data share:
/// the header is held fixed and the fuzzer mutates only the
/// compressed stream and its trailer. A mutated file must be refused (with the
/// one-line message) or load exactly the voxels of the unmutated file; loading
/// anything else is a finding.
///
/// The unmutated file is built here with zlib from samples(); the seeds in
/// fuzz/seeds/<target>/ are streams of the same samples written by Python's
/// gzip and zlib modules (fuzz/seeds/compressed_seeds.py), so that the
/// fuzzer starts from valid streams of several shapes.
#pragma once

#include "FuzzInput.h"

#include "volume/Grids.h"
#include "volume/Volume.h"

#include <zlib.h>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

namespace voxhap::fuzz {

/// The volume every seed holds: int16 little endian, x fastest. Small, so
/// that a stream stays far below the 4 KiB inputs of tools/fuzz.sh.
constexpr int kCompressedNx = 9, kCompressedNy = 7, kCompressedNz = 5;

/// Stored value at (i, j, k); the same formula as compressed_seeds.py. Some
/// values fall below the -950 HU air threshold, so that activity is compared too.
inline std::int16_t compressedSample(int i, int j, int k)
{
    return std::int16_t((i * 73 + j * 151 + k * 233) % 1500 - 1000);
}

inline std::string compressedSamples()
{
    std::string out;
    for (int k = 0; k < kCompressedNz; ++k)
        for (int j = 0; j < kCompressedNy; ++j)
            for (int i = 0; i < kCompressedNx; ++i) {
                const auto v = std::uint16_t(compressedSample(i, j, k));
                out += char(v & 0xff);
                out += char(v >> 8);
            }
    return out;
}

/// @p data deflated in zlib's wrapper for @p windowBits (15 + 16: gzip, 15: zlib).
inline std::string deflated(const std::string& data, int windowBits)
{
    z_stream z{};
    if (deflateInit2(&z, 6, Z_DEFLATED, windowBits, 8, Z_DEFAULT_STRATEGY) != Z_OK) finding("deflateInit2 failed");
    std::string out(deflateBound(&z, uLong(data.size())) + 32, '\0');
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
    z.avail_in = uInt(data.size());
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = uInt(out.size());
    if (deflate(&z, Z_FINISH) != Z_STREAM_END) finding("deflate failed");
    out.resize(z.total_out);
    deflateEnd(&z);
    return out;
}

/// The first voxel where @p a and @p b differ in value or activity, or a
/// difference of extent; empty when they hold the same voxels.
inline std::string voxelDifference(const volume::Volume& a, const volume::Volume& b)
{
    if (a.indexBox() != b.indexBox()) return "index boxes differ";
    const auto ga = volume::huGrid(a), gb = volume::huGrid(b);
    if (!ga || !gb) return "no hu grid";
    // Straight tree queries, no accessors: a registered accessor trips UBSan
    // inside TBB's concurrent_hash_map, where OpenVDB registers it.
    const auto& x = ga->tree();
    const auto& y = gb->tree();
    const auto box = a.indexBox();
    for (int k = box.min.z(); k <= box.max.z(); ++k)
        for (int j = box.min.y(); j <= box.max.y(); ++j)
            for (int i = box.min.x(); i <= box.max.x(); ++i) {
                const openvdb::Coord c(i, j, k);
                float u = 0, v = 0;
                const bool uOn = x.probeValue(c, u), vOn = y.probeValue(c, v);
                if (u != v || uOn != vOn) {
                    return "voxel (" + std::to_string(i) + ", " + std::to_string(j) + ", " + std::to_string(k) +
                        ") is " + std::to_string(v) + (vOn ? " (active)" : " (inactive)") + ", unmutated " +
                        std::to_string(u);
                }
            }
    if (ga->activeVoxelCount() != gb->activeVoxelCount()) return "active voxel counts differ";
    return {};
}

/// One content-comparing target: the file is @p header followed by the input.
class CompressedTarget {
public:
    using Load = std::function<volume::Volume(const std::filesystem::path&)>;
    /// @param suffix    the scratch file's extension (readers look at it)
    /// @param header    the fixed bytes before the stream (empty for .nii.gz)
    /// @param reference the unmutated stream
    CompressedTarget(const std::string& suffix, std::string header, const std::string& reference, Load load)
        : mFile(suffix), mHeader(std::move(header)), mLoad(std::move(load))
    {
        try {
            mReference = mLoad(write(reinterpret_cast<const std::uint8_t*>(reference.data()), reference.size()));
        } catch (const Error& e) {
            finding(std::string("the unmutated file is refused: ") + e.what());
        }
    }

    int run(const std::uint8_t* data, std::size_t size)
    {
        const std::filesystem::path& p = write(data, size);
        std::optional<volume::Volume> loaded;
        try {
            loaded = mLoad(p);
        } catch (const Error& e) {
            checkRefusal(e, p.string());
            return 0;
        }
        const std::string diff = voxelDifference(*mReference, *loaded);
        if (!diff.empty()) finding("a mutated stream was accepted with different voxels: " + diff);
        return 0;
    }

private:
    const std::filesystem::path& write(const std::uint8_t* data, std::size_t size)
    {
        std::string bytes = mHeader;
        bytes.append(reinterpret_cast<const char*>(data), size);
        return mFile.write(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    }

    ScratchFile mFile;
    std::string mHeader;
    Load mLoad;
    std::optional<volume::Volume> mReference;
};

} // namespace voxhap::fuzz
