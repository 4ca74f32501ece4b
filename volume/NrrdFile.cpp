// SPDX-License-Identifier: Apache-2.0
/// @file NrrdFile.cpp
/// @brief NRRD0004 header by hand, voxels slab by slab (raw or gzip); the reader
/// parses attached headers itself (Debian has no maintained NRRD library
/// outside ITK/VTK, which the volume library must not pull in).

#include "volume/NrrdFile.h"

#include "volume/AtomicFile.h"
#include "volume/Errors.h"
#include "volume/Grids.h"

#include <openvdb/tools/Dense.h>
#include <zlib.h>

#include <bit>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>
#include <fstream>
#include <iomanip>
#include <limits>
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

template <typename GridT>
void writeVoxels(const GridT& grid, const IndexBox& box, Sink& sink)
{
    using ValueT = typename GridT::ValueType;
    const Vec3i d = box.dims();
    constexpr int kSlab = 8; // slices per block: memory stays at a few slices
    std::vector<ValueT> buf(std::size_t(d.x()) * std::size_t(d.y()) * kSlab);
    for (int k0 = box.min.z(); k0 <= box.max.z(); k0 += kSlab) {
        const int k1 = std::min(k0 + kSlab - 1, box.max.z());
        const openvdb::CoordBBox bb(openvdb::Coord(box.min.x(), box.min.y(), k0), openvdb::Coord(box.max.x(), box.max.y(), k1));
        openvdb::tools::Dense<ValueT, openvdb::tools::LayoutXYZ> dense(bb, buf.data());
        openvdb::tools::copyToDense(grid, dense);
        sink.write(buf.data(), sizeof(ValueT) * std::size_t(d.x()) * std::size_t(d.y()) * std::size_t(k1 - k0 + 1));
    }
}

} // namespace

void saveNrrd(const Volume& v, Channel c, const std::filesystem::path& file, NrrdEncoding encoding)
{
    if (!v.has(c)) throw ValueError(file.string() + ": the volume has no '" + std::string(channelName(c)) + "' grid to save");
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
    h << "voxhap_channel:=" << channelName(c) << "\n";
    h << "voxhap_units:=" << (c == Channel::Hu ? v.metadata().huUnits : c == Channel::T1 ? v.metadata().t1Units : "tissue id") << "\n";
    if (!v.metadata().modality.empty()) h << "voxhap_modality:=" << v.metadata().modality << "\n";
    h << "\n";

    writeStreamAtomically(file, [&](std::ostream& out) {
        const std::string header = h.str();
        out.write(header.data(), std::streamsize(header.size()));
        Sink sink(out, encoding);
        if (c == Channel::Label) writeVoxels(*labelGrid(v), box, sink);
        else writeVoxels(c == Channel::Hu ? *huGrid(v) : *t1Grid(v), box, sink);
        sink.finish();
    });
}

namespace {

std::string lower(std::string s)
{
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

std::string trimmed(std::string_view s)
{
    std::size_t a = 0, b = s.size();
    while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
    while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
    return std::string(s.substr(a, b - a));
}

/// "(a,b,c)" → vector; "none" is refused (every axis must be spatial).
Vec3d parseVector(const std::string& text, const std::string& file, const std::string& field)
{
    double v[3];
    char open = 0, c1 = 0, c2 = 0, close = 0;
    std::istringstream in(text);
    if (!(in >> open >> v[0] >> c1 >> v[1] >> c2 >> v[2] >> close) || open != '(' || c1 != ',' || c2 != ',' ||
        close != ')' || !std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
        throw IoError(file + ": " + field + ": expected (x,y,z) with finite numbers, got '" + text + "'");
    }
    return Vec3d(v[0], v[1], v[2]);
}

SampleType parseType(const std::string& t, const std::string& file)
{
    static const std::map<std::string, SampleType> kTypes{
        {"signed char", SampleType::Int8},   {"int8", SampleType::Int8},       {"int8_t", SampleType::Int8},
        {"uchar", SampleType::UInt8},        {"unsigned char", SampleType::UInt8}, {"uint8", SampleType::UInt8},
        {"uint8_t", SampleType::UInt8},      {"short", SampleType::Int16},     {"short int", SampleType::Int16},
        {"signed short", SampleType::Int16}, {"signed short int", SampleType::Int16}, {"int16", SampleType::Int16},
        {"int16_t", SampleType::Int16},      {"ushort", SampleType::UInt16},   {"unsigned short", SampleType::UInt16},
        {"unsigned short int", SampleType::UInt16}, {"uint16", SampleType::UInt16}, {"uint16_t", SampleType::UInt16},
        {"int", SampleType::Int32},          {"signed int", SampleType::Int32}, {"int32", SampleType::Int32},
        {"int32_t", SampleType::Int32},      {"uint", SampleType::UInt32},     {"unsigned int", SampleType::UInt32},
        {"uint32", SampleType::UInt32},      {"uint32_t", SampleType::UInt32}, {"float", SampleType::Float32},
        {"double", SampleType::Float64},
    };
    const auto it = kTypes.find(lower(t));
    if (it == kTypes.end()) throw IoError(file + ": type: '" + t + "' is not a supported sample type");
    return it->second;
}

} // namespace

NrrdHeader parseNrrdHeader(std::string_view text, const std::string& file)
{
    if (text.size() < 8 || text.substr(0, 7) != "NRRD000" || text[7] < '1' || text[7] > '5') {
        throw IoError(file + ": magic: not a NRRD file (expected NRRD0001 to NRRD0005)");
    }
    std::map<std::string, std::string> fields;
    NrrdHeader h;
    std::size_t pos = text.find('\n');
    bool ended = false;
    while (pos != std::string_view::npos && pos + 1 <= text.size()) {
        const std::size_t next = text.find('\n', pos + 1);
        if (next == std::string_view::npos) break;
        std::string_view line = text.substr(pos + 1, next - pos - 1);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        pos = next;
        if (line.empty()) {
            ended = true;
            h.dataOffset = next + 1;
            break;
        }
        if (line.front() == '#') continue;
        const std::size_t kv = line.find(":=");
        if (kv != std::string_view::npos) {
            h.keyValues[trimmed(line.substr(0, kv))] = trimmed(line.substr(kv + 2));
            continue;
        }
        const std::size_t colon = line.find(": ");
        if (colon == std::string_view::npos) throw IoError(file + ": header: malformed line '" + std::string(line) + "'");
        const std::string key = lower(trimmed(line.substr(0, colon)));
        if (fields.count(key)) throw IoError(file + ": " + key + ": given twice");
        fields[key] = trimmed(line.substr(colon + 2));
    }
    if (!ended) throw IoError(file + ": header: no blank line ends the header (truncated file?)");

    const auto need = [&](const std::string& key) -> const std::string& {
        const auto it = fields.find(key);
        if (it == fields.end()) throw IoError(file + ": " + key + ": missing");
        return it->second;
    };
    if (fields.count("data file") || fields.count("datafile")) {
        throw IoError(file + ": data file: detached data (.nhdr) is not supported; save as a single .nrrd");
    }
    for (const char* skip : {"line skip", "lineskip", "byte skip", "byteskip"}) {
        if (fields.count(skip) && fields[skip] != "0") throw IoError(file + ": " + skip + ": only 0 is supported");
    }
    h.layout.type = parseType(need("type"), file);
    if (need("dimension") != "3") throw IoError(file + ": dimension: " + fields["dimension"] + " (only 3D volumes are read)");
    {
        std::istringstream in(need("sizes"));
        long long s[3];
        if (!(in >> s[0] >> s[1] >> s[2]) || !(in >> std::ws).eof()) {
            throw IoError(file + ": sizes: expected three whole numbers, got '" + fields["sizes"] + "'");
        }
        for (int a = 0; a < 3; ++a) {
            if (s[a] < 1 || s[a] > (1 << 24)) throw IoError(file + ": sizes: '" + fields["sizes"] + "' out of range");
            h.layout.dims[a] = int(s[a]);
        }
    }
    const std::string enc = lower(need("encoding"));
    if (enc == "gzip" || enc == "gz") h.gzip = true;
    else if (enc != "raw") throw IoError(file + ": encoding: '" + enc + "' is not supported (raw or gzip)");
    if (sampleBytes(h.layout.type) > 1) {
        const std::string e = lower(need("endian"));
        if (e != "little" && e != "big") throw IoError(file + ": endian: '" + e + "' (little or big)");
        h.layout.bigEndian = e == "big";
    }
    const std::string space = lower(need("space"));
    Vec3d flip(1, 1, 1); // file space → LPS
    if (space == "right-anterior-superior" || space == "ras") flip = Vec3d(-1, -1, 1);
    else if (space == "left-anterior-superior" || space == "las") flip = Vec3d(1, -1, 1);
    else if (space != "left-posterior-superior" && space != "lps") {
        throw IoError(file + ": space: '" + space + "' (LPS, RAS or LAS expected)");
    }
    {
        const std::string& dirs = need("space directions");
        std::istringstream in(dirs);
        for (int a = 0; a < 3; ++a) {
            std::string tok;
            if (!(in >> tok)) throw IoError(file + ": space directions: expected three vectors, got '" + dirs + "'");
            const Vec3d d = parseVector(tok, file, "space directions").cwiseProduct(flip);
            h.geometry.spacing[a] = d.norm();
            if (!(h.geometry.spacing[a] > 0)) throw IoError(file + ": space directions: axis " + std::to_string(a) + " has zero length");
            h.geometry.direction.col(a) = d / h.geometry.spacing[a];
        }
    }
    if (fields.count("space origin")) h.geometry.origin = parseVector(fields["space origin"], file, "space origin").cwiseProduct(flip);
    try {
        makeTransform(h.geometry); // same checks as every Volume: unit, non-degenerate directions
    } catch (const ValueError& e) {
        throw IoError(file + ": space directions: " + e.what());
    }
    return h;
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
    const std::size_t cut = std::min(end == std::string::npos ? text.size() : end + 2, endCr == std::string::npos ? text.size() : endCr + 4);
    const NrrdHeader h = parseNrrdHeader(std::string_view(text).substr(0, cut), name);
    checkRasterSize(h.layout.dims, options.memoryCapBytes, name, "sizes");

    Channel channel = options.channel;
    if (auto it = h.keyValues.find("voxhap_channel"); it != h.keyValues.end()) {
        if (it->second == "hu") channel = Channel::Hu;
        else if (it->second == "t1") channel = Channel::T1;
        else if (it->second == "label") channel = Channel::Label;
        else throw IoError(name + ": voxhap_channel: '" + it->second + "' (hu, t1 or label)");
    }
    ByteSource src(file, h.dataOffset, h.gzip);
    Volume v(h.geometry, IndexBox{Vec3i::Zero(), h.layout.dims - Vec3i::Ones()});
    v.setGrid(channel, readRaster(src, h.layout, channel, options, name));
    auto& md = v.metadata();
    md.source = file.filename().string();
    if (auto it = h.keyValues.find("voxhap_modality"); it != h.keyValues.end()) md.modality = it->second;
    if (auto it = h.keyValues.find("voxhap_units"); it != h.keyValues.end()) {
        (channel == Channel::T1 ? md.t1Units : md.huUnits) = it->second;
    }
    return v;
}

} // namespace voxhap::volume
