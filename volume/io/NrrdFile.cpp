// SPDX-License-Identifier: Apache-2.0
/// @file NrrdFile.cpp
/// @brief NRRD0004 header by hand, voxels slab by slab (raw or gzip); the reader
/// parses attached headers itself (Debian has no maintained NRRD library
/// outside ITK/VTK, which the volume library must not pull in).

#include "volume/io/NrrdFile.h"

#include "core/AtomicFile.h"
#include "core/Errors.h"
#include "volume/Grids.h"

#include <openvdb/tools/Dense.h>
#include <zlib.h>

#include <bit>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

namespace voxhap::volume {

namespace {

static_assert(std::endian::native == std::endian::little, "the header says \"endian: little\"");

/// Streams bytes to a file, raw or through a gzip deflater.
class Sink {
public:
    Sink(std::ostream& out, NrrdEncoding enc) : mOut(out), mGzip(enc == NrrdEncoding::Gzip)
    {
        // windowBits 15 + 16: a gzip wrapper, which NRRD's "gzip" encoding means.
        // Level 1: about 5x faster than the default on CT, files ~10% larger.
        if (mGzip && deflateInit2(&mZ, Z_BEST_SPEED, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
            throw std::runtime_error("zlib initialisation failed");
        }
    }
    ~Sink()
    {
        if (mGzip) deflateEnd(&mZ);
    }
    void write(const void* data, std::size_t n) { pump(data, n, Z_NO_FLUSH); }
    void finish() { pump(nullptr, 0, Z_FINISH); }

private:
    void pump(const void* data, std::size_t n, int flush)
    {
        if (!mGzip) {
            if (n) mOut.write(static_cast<const char*>(data), std::streamsize(n));
            return;
        }
        mZ.next_in = static_cast<Bytef*>(const_cast<void*>(data));
        mZ.avail_in = uInt(n);
        char buf[1 << 16];
        int rc = Z_OK;
        do {
            mZ.next_out = reinterpret_cast<Bytef*>(buf);
            mZ.avail_out = sizeof buf;
            rc = deflate(&mZ, flush);
            if (rc == Z_STREAM_ERROR) throw std::runtime_error("zlib deflate failed");
            mOut.write(buf, std::streamsize(sizeof buf - mZ.avail_out));
        } while (mZ.avail_out == 0 || (flush == Z_FINISH && rc != Z_STREAM_END));
    }

    std::ostream& mOut;
    bool mGzip;
    z_stream mZ{};
};

template <typename GridT> void writeVoxels(const GridT& grid, const IndexBox& box, Sink& sink)
{
    using ValueT = typename GridT::ValueType;
    const Vec3i d = box.dims();
    constexpr int kSlab = 8; // slices per block: memory stays at a few slices
    std::vector<ValueT> buf(std::size_t(d.x()) * std::size_t(d.y()) * kSlab);
    for (int k0 = box.min.z(); k0 <= box.max.z(); k0 += kSlab) {
        const int k1 = std::min(k0 + kSlab - 1, box.max.z());
        const openvdb::CoordBBox bb(
            openvdb::Coord(box.min.x(), box.min.y(), k0), openvdb::Coord(box.max.x(), box.max.y(), k1));
        openvdb::tools::Dense<ValueT, openvdb::tools::LayoutXYZ> dense(bb, buf.data());
        openvdb::tools::copyToDense(grid, dense);
        sink.write(buf.data(), sizeof(ValueT) * std::size_t(d.x()) * std::size_t(d.y()) * std::size_t(k1 - k0 + 1));
    }
}

} // namespace

void saveNrrd(const Volume& v, Channel c, const std::filesystem::path& file, NrrdEncoding encoding, NrrdKeys keys)
{
    if (!v.has(c))
        throw ValueError(file.string() + ": the volume has no '" + std::string(channelName(c)) + "' grid to save");
    const IndexBox& box = v.indexBox();
    if (box.empty()) throw ValueError(file.string() + ": the volume's extent is empty");
    const Geometry g = v.geometry();
    const Vec3d origin = v.indexToWorld(box.min.cast<double>());

    std::ostringstream h;
    h << std::setprecision(std::numeric_limits<double>::max_digits10);
    h << "NRRD0004\n# written by voxhap; format: http://teem.sourceforge.net/nrrd/format.html\n";
    h << "type: " << (c == Channel::Label ? "int32" : "float") << "\n";
    h << "dimension: 3\nspace: left-posterior-superior\n";
    const Vec3i d = box.dims();
    h << "sizes: " << d.x() << ' ' << d.y() << ' ' << d.z() << "\n";
    h << "space directions:";
    for (int a = 0; a < 3; ++a) {
        const Vec3d axis = g.direction.col(a) * g.spacing[a];
        h << " (" << axis.x() << ',' << axis.y() << ',' << axis.z() << ')';
    }
    h << "\nkinds: domain domain domain\nendian: little\n";
    h << "encoding: " << (encoding == NrrdEncoding::Gzip ? "gzip" : "raw") << "\n";
    h << "space origin: (" << origin.x() << ',' << origin.y() << ',' << origin.z() << ")\n";
    if (keys == NrrdKeys::Voxhap) {
        h << "voxhap_channel:=" << channelName(c) << "\n";
        h << "voxhap_units:="
          << (c == Channel::Hu                 ? v.metadata().huUnits
                     : c == Channel::T1        ? v.metadata().t1Units
                     : c == Channel::Intensity ? v.metadata().intensityUnits
                                               : std::string("tissue id"))
          << "\n";
        // The typed facts (VolumeMetadata.h), one line each: their texts hold no line break.
        for (const auto& [name, text] : metadataFacts(v.metadata())) h << "voxhap_" << name << ":=" << text << "\n";
    }
    h << "\n";

    writeStreamAtomically(file, [&](std::ostream& out) {
        const std::string header = h.str();
        out.write(header.data(), std::streamsize(header.size()));
        Sink sink(out, encoding);
        if (c == Channel::Label)
            writeVoxels(*labelGrid(v), box, sink);
        else
            writeVoxels(c == Channel::Hu ? *huGrid(v) : c == Channel::T1 ? *t1Grid(v) : *intensityGrid(v), box, sink);
        sink.finish();
    });
}

Volume loadNrrd(const std::filesystem::path& file, const RasterOptions& options)
{
    const std::string name = file.string();
    std::ifstream in(file, std::ios::binary);
    if (!in) throw IoError(name + ": cannot open");
    // Headers are a few hundred bytes; 64 KiB bounds what a corrupt file makes us read.
    constexpr std::size_t kMaxHeader = 1 << 16;
    std::string text(kMaxHeader, '\0');
    in.read(text.data(), std::streamsize(text.size()));
    text.resize(std::size_t(in.gcount()));
    const std::size_t end = text.find("\n\n");
    const std::size_t endCr = text.find("\r\n\r\n");
    const std::size_t cut = std::min(
        end == std::string::npos ? text.size() : end + 2, endCr == std::string::npos ? text.size() : endCr + 4);
    const NrrdHeader h = parseNrrdHeader(std::string_view(text).substr(0, cut), name);
    checkRasterSize(h.layout.dims, options.memoryCapBytes, name, "sizes");

    Channel channel = options.channel;
    if (auto it = h.keyValues.find("voxhap_channel"); it != h.keyValues.end()) {
        if (it->second == "hu")
            channel = Channel::Hu;
        else if (it->second == "t1")
            channel = Channel::T1;
        else if (it->second == "label")
            channel = Channel::Label;
        else if (it->second == "intensity")
            channel = Channel::Intensity;
        else
            throw IoError(name + ": voxhap_channel: '" + it->second + "' (hu, t1, intensity or label)");
    }
    ByteSource src(file, h.dataOffset, h.gzip);
    Volume v(h.geometry, IndexBox{Vec3i::Zero(), h.layout.dims - Vec3i::Ones()});
    if (channel == Channel::Label) {
        // Labels (e.g. `voxhap segment --export`) read through the float path, which
        // holds every int32 id up to 2^24 exactly, with no air threshold; 0 stays inactive.
        RasterOptions keepAll = options;
        keepAll.airHu = -std::numeric_limits<float>::max();
        const auto values = openvdb::gridPtrCast<FloatGrid>(readRaster(src, h.layout, Channel::Hu, keepAll, name));
        auto labels = LabelGrid::create(kAirLabel);
        auto acc = labels->getAccessor();
        for (auto it = values->cbeginValueOn(); it; ++it) {
            const float x = *it;
            if (x != std::round(x) || std::abs(x) > float(1 << 24)) {
                throw IoError(name + ": data: label " + std::to_string(x) + " is not an integer id");
            }
            if (x == 0.0f) continue;
            if (it.isVoxelValue())
                acc.setValue(it.getCoord(), std::int32_t(x));
            else
                labels->tree().fill(it.getBoundingBox(), std::int32_t(x), true);
        }
        v.setGrid(channel, labels);
    } else {
        v.setGrid(channel, readRaster(src, h.layout, channel, options, name));
    }
    src.finish(); // the whole compressed stream must check out, not just the bytes the voxels took
    auto& md = v.metadata();
    md.source = file.filename().string();
    if (auto it = h.keyValues.find("voxhap_units"); it != h.keyValues.end()) {
        (channel == Channel::T1                 ? md.t1Units
                : channel == Channel::Intensity ? md.intensityUnits
                                                : md.huUnits) = it->second;
    }
    for (const auto& [key, value] : h.keyValues) {
        if (key.rfind("voxhap_", 0) != 0) continue;
        try {
            setMetadataFact(md, std::string_view(key).substr(7), value, name);
        } catch (const ValueError& e) {
            throw IoError(e.what());
        }
    }
    // A voxhap NRRD that names its channel hu says it holds CT numbers: the
    // loaders take it as CT without looking at the values.
    if (channel == Channel::Hu && h.keyValues.count("voxhap_channel")) {
        md.modalitySource = FactSource::Header;
        md.modalityReason = "declared by the file's voxhap_channel:=hu";
    }
    return v;
}

} // namespace voxhap::volume
