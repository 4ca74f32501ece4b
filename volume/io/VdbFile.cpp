// SPDX-License-Identifier: Apache-2.0
/// @file VdbFile.cpp
/// @brief .vdb reading and writing through openvdb::io::File.

#include "volume/io/VdbFile.h"

#include "core/AtomicFile.h"
#include "core/Errors.h"
#include "volume/Grids.h"

#include <nlohmann/json.hpp>
#include <openvdb/io/File.h>
#include <openvdb/points/StreamCompression.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

namespace voxhap::volume {

namespace {

constexpr const char* kPrefix = "voxhap.";
constexpr const char* kFormatKey = "voxhap.format";
constexpr int kFormatVersion = 1;

void putString(openvdb::MetaMap& meta, const std::string& key, const std::string& value)
{
    meta.insertMeta(kPrefix + key, openvdb::StringMetadata(value));
}

/// An OpenVDB message on one line.
std::string oneLineMessage(std::string s)
{
    std::replace_if(
        s.begin(), s.end(), [](char ch) { return ch == '\n' || ch == '\r'; }, ' ');
    return s;
}

std::string getString(const openvdb::MetaMap& meta, const std::string& key, const std::string& fallback = {})
{
    if (auto m = meta.getMetadata<openvdb::StringMetadata>(kPrefix + key)) return m->value();
    return fallback;
}

// ---------------------------------------------------------------------------
// The container walk (see loadVdb in VdbFile.h). It follows OpenVDB 10's
// readers field by field (io/Archive.cc readHeader and readGrid,
// io/GridDescriptor.cc, MetaMap::readMeta, Metadata::read,
// io/DelayedLoadMetadata.cc, math/Maps.h, tree/RootNode.h,
// tree/InternalNode.h and tree/LeafNode.h readTopology/readBuffers,
// io/Compression.h readCompressedValues and io/Compression.cc), reading
// nothing but fixed-size fields, so that every length OpenVDB will allocate
// from is checked against the bytes that remain before OpenVDB sees it.

namespace vdbwalk {

constexpr std::int64_t kVdbMagic = 0x56444220;
constexpr std::uint32_t kOldestVersion = 222; // older files have other node layouts
constexpr std::uint32_t kNodeMaskCompression = 222;
constexpr std::uint32_t kNewestVersion = 224;
constexpr std::uint32_t kCompressZip = 0x1, kCompressActiveMask = 0x2, kCompressBlosc = 0x4;
constexpr std::size_t kBloscHeader = 16;

/// @p s with every byte outside printable ASCII as '?': file bytes in a one-line message.
std::string printable(std::string s)
{
    for (char& ch : s) {
        if ((unsigned char)ch < 0x20 || (unsigned char)ch > 0x7e) ch = '?';
    }
    return s;
}

std::string mib(std::uint64_t bytes) { return std::to_string((bytes + (1u << 20) - 1) >> 20) + " MiB"; }

/// A bounded reader over the mapped file: reading past `end` is a refusal.
class Cursor {
public:
    Cursor(const std::string& file, const unsigned char* data, std::size_t end, std::size_t pos = 0)
        : mFile(&file), mData(data), mEnd(end), mPos(pos)
    {
    }
    std::size_t pos() const { return mPos; }
    std::size_t remaining() const { return mEnd - mPos; }

    [[noreturn]] void fail(const std::string& field, std::size_t offset, const std::string& what) const
    {
        throw IoError(*mFile + ": " + field + " at byte " + std::to_string(offset) + ": " + what);
    }
    void need(std::uint64_t n, const std::string& field, std::size_t offset) const
    {
        if (n > remaining()) {
            fail(field, offset,
                "needs " + std::to_string(n) + " bytes, " + std::to_string(remaining()) + " remain" +
                    (mEnd == mWholeFile ? " in the file" : " in this grid"));
        }
    }
    void bound(std::size_t wholeFile) { mWholeFile = wholeFile; }

    template <typename T> T get(const std::string& field)
    {
        need(sizeof(T), field, mPos);
        T v;
        std::memcpy(&v, mData + mPos, sizeof(T));
        mPos += sizeof(T);
        return v;
    }
    void skip(std::uint64_t n, const std::string& field)
    {
        need(n, field, mPos);
        mPos += std::size_t(n);
    }
    const unsigned char* here() const { return mData + mPos; }

    /// A length-prefixed string (openvdb::readString), at most @p maxLen bytes.
    std::string string(const std::string& field, std::uint32_t maxLen)
    {
        const std::size_t at = mPos;
        const auto n = get<std::uint32_t>(field + " length");
        if (n > maxLen)
            fail(field + " length", at, std::to_string(n) + " bytes, over the limit of " + std::to_string(maxLen));
        need(n, field, at);
        std::string s(reinterpret_cast<const char*>(mData + mPos), n);
        mPos += n;
        return s;
    }

private:
    const std::string* mFile;
    const unsigned char* mData;
    std::size_t mEnd;
    std::size_t mPos;
    std::size_t mWholeFile = 0;
};

/// What the walk of one grid found.
struct GridWalk {
    std::uint64_t rootChildren = 0, internalNodes = 0, leaves = 0;
    std::uint64_t delayedLoadCount = 0; ///< entries the delayed-load metadata declares
    std::size_t delayedLoadOffset = 0;
};

/// Blosc's 16-byte header: the declared sizes must be the chunk's.
/// The length OpenVDB pads a short buffer to before Blosc compresses it.
constexpr std::uint64_t kBloscPadBytes = std::uint64_t(openvdb::compression::BLOSC_PAD_BYTES);

void checkBlosc(Cursor& c, std::size_t at, std::uint64_t chunk, std::uint64_t expected, const std::string& field)
{
    if (chunk < kBloscHeader)
        c.fail(field, at, "a Blosc chunk of " + std::to_string(chunk) + " bytes is shorter than its header");
    std::uint32_t nbytes = 0, cbytes = 0;
    std::memcpy(&nbytes, c.here() + 4, 4);
    std::memcpy(&cbytes, c.here() + 12, 4);
    if (nbytes != expected) {
        c.fail(field, at,
            "Blosc header declares " + std::to_string(nbytes) + " bytes, expected " + std::to_string(expected));
    }
    if (cbytes != chunk) {
        c.fail(field, at,
            "Blosc header declares a " + std::to_string(cbytes) + "-byte chunk in " + std::to_string(chunk) + " bytes");
    }
}

/// Metadata values: fixed-size types must declare their size (OpenVDB reads
/// sizeof(T) whatever the declared length), strings and unknown types any
/// length that fits, the delayed-load table its own layout.
std::size_t fixedMetadataSize(const std::string& type)
{
    static const std::map<std::string, std::size_t> sizes = {{"bool", 1}, {"double", 8}, {"float", 4}, {"int32", 4},
        {"int64", 8}, {"vec2i", 8}, {"vec2s", 8}, {"vec2d", 16}, {"vec3i", 12}, {"vec3s", 12}, {"vec3d", 24},
        {"vec4i", 16}, {"vec4s", 16}, {"vec4d", 32}, {"mat4s", 64}, {"mat4d", 128}};
    const auto it = sizes.find(type);
    return it == sizes.end() ? 0 : it->second;
}

void walkDelayedLoad(Cursor& c, std::uint32_t numBytes, const std::string& field, GridWalk* grid)
{
    const std::size_t start = c.pos();
    if (numBytes == 0) return;
    const auto count = c.get<std::uint32_t>(field + " entry count");
    if (grid) {
        grid->delayedLoadCount = count;
        grid->delayedLoadOffset = start;
    } else {
        c.fail(field, start, "delayed-load metadata outside a grid");
    }
    for (int part = 0; part < 2; ++part) {
        const std::size_t elem = part == 0 ? 1 : 8;
        const std::string what = field + (part == 0 ? " delayed-load mask table" : " delayed-load size table");
        const std::size_t at = c.pos();
        const auto bytes = c.get<std::uint32_t>(what + " length");
        if (part == 1 && bytes == std::numeric_limits<std::uint32_t>::max()) break; // no size table
        if (bytes > 0) {
            c.need(bytes, what, at);
            // OpenVDB pads a table shorter than BLOSC_PAD_BYTES with zeros to
            // that length before compressing it (compression::bloscCompress),
            // so the chunk then declares the padded length.
            const std::uint64_t table = std::uint64_t(count) * elem;
            checkBlosc(c, at, bytes, std::max<std::uint64_t>(table, kBloscPadBytes), what);
            c.skip(bytes, what);
        } else {
            c.skip(std::uint64_t(count) * elem, what);
        }
    }
    if (c.pos() - start > numBytes) {
        c.fail(field, start,
            "takes " + std::to_string(c.pos() - start) + " bytes, its length says " + std::to_string(numBytes));
    }
    c.skip(numBytes - (c.pos() - start), field);
}

void walkMetadata(Cursor& c, const std::string& where, GridWalk* grid)
{
    const std::size_t at = c.pos();
    const auto count = c.get<std::uint32_t>(where + " count");
    if (std::uint64_t(count) * 12 > c.remaining()) {
        c.fail(where + " count", at,
            std::to_string(count) + " entries cannot fit in the " + std::to_string(c.remaining()) +
                " bytes that remain");
    }
    for (std::uint32_t i = 0; i < count; ++i) {
        const std::string entry = where + " entry " + std::to_string(i);
        const std::string name = c.string(entry + " name", 1u << 16);
        const std::string type = c.string(entry + " type", 256);
        const std::size_t valueAt = c.pos();
        const auto numBytes = c.get<std::uint32_t>(entry + " value length");
        c.need(numBytes, entry + " value", valueAt);
        const std::string field = entry + " value";
        if (const std::size_t fixed = fixedMetadataSize(type)) {
            if (numBytes != fixed) {
                c.fail(field + " length", valueAt,
                    std::to_string(numBytes) + " bytes for a " + printable(type) + ", which takes " +
                        std::to_string(fixed));
            }
            c.skip(numBytes, field);
        } else if (type == "string") {
            c.skip(numBytes, field);
        } else if (type == "__delayedload") {
            walkDelayedLoad(c, numBytes, field, grid);
        } else if (openvdb::Metadata::isRegisteredType(type)) {
            c.fail(field, valueAt, "metadata of type '" + printable(type) + "' is not supported");
        } else {
            c.skip(numBytes, field); // unknown types are kept as raw bytes of the declared length
        }
    }
}

/// Sizes of the grids voxhap reads (float and int32 trees share them).
struct TreeShape {
    std::size_t valueSize = 4;  ///< bytes per value in memory
    std::size_t storedSize = 4; ///< bytes per stored voxel value (2 for half floats)
    std::uint32_t compression = 0;
    std::uint32_t version = 224;
};

/// io::readCompressedValues for a node of @p count values whose value mask
/// has @p active bits on and is @p maskBytes long.
void walkValues(Cursor& c, const TreeShape& t, std::uint64_t count, std::uint64_t active, std::size_t maskBytes,
    const std::string& field)
{
    int meta = 6; // NO_MASK_AND_ALL_VALS
    if (t.version >= kNodeMaskCompression) {
        const std::size_t at = c.pos();
        meta = c.get<std::int8_t>(field + " compression flag");
        if (meta < 0 || meta > 6)
            c.fail(field + " compression flag", at, "value " + std::to_string(meta) + " is not 0 to 6");
    }
    if (meta == 2 || meta == 4 || meta == 5) c.skip(t.valueSize, field + " inactive value");
    if (meta == 5) c.skip(t.valueSize, field + " second inactive value");
    if (meta == 3 || meta == 4 || meta == 5) c.skip(maskBytes, field + " selection mask");
    const bool maskCompressed = (t.compression & kCompressActiveMask) && meta != 6 && t.version >= kNodeMaskCompression;
    const std::uint64_t n = maskCompressed ? active : count;
    const std::uint64_t bytes = n * t.storedSize; // half floats in nodes and leaves alike
    if (t.compression & (kCompressBlosc | kCompressZip)) {
        const std::size_t at = c.pos();
        const auto chunk = c.get<std::int64_t>(field + " compressed size");
        if (chunk <= 0) {
            if (std::uint64_t(-(chunk + 1)) + 1 != bytes && !(chunk == 0 && bytes == 0)) {
                c.fail(field + " compressed size", at,
                    "an uncompressed chunk of " + std::to_string(-(chunk + 1)) + "+1 bytes, expected " +
                        std::to_string(bytes));
            }
            c.skip(bytes, field);
        } else {
            c.need(std::uint64_t(chunk), field, at);
            if (t.compression & kCompressBlosc) checkBlosc(c, at, std::uint64_t(chunk), bytes, field);
            c.skip(std::uint64_t(chunk), field);
        }
    } else {
        c.skip(bytes, field);
    }
}

std::uint64_t popcount(const unsigned char* p, std::size_t n)
{
    std::uint64_t k = 0;
    for (std::size_t i = 0; i < n; ++i) k += std::uint64_t(__builtin_popcount(p[i]));
    return k;
}

// Node layouts of the 5-4-3 trees: log2 dimension per level, root child first.
constexpr int kLog2[3] = {5, 4, 3};

/// InternalNode::readTopology at @p level (0: the root's children), then its
/// children's, collecting the leaves' active counts in @p leafActive.
void walkInternal(Cursor& c, const TreeShape& t, int level, GridWalk& w, std::vector<std::uint32_t>& leafActive)
{
    const std::uint64_t values = std::uint64_t(1) << (3 * kLog2[level]);
    const std::size_t maskBytes = std::size_t(values / 8);
    const std::string field = level == 0 ? "upper internal node" : "lower internal node";
    c.need(2 * maskBytes, field + " masks", c.pos());
    const std::size_t childMaskAt = c.pos();
    const unsigned char* childMask = c.here();
    c.skip(maskBytes, field + " child mask");
    const std::uint64_t active = popcount(c.here(), maskBytes);
    c.skip(maskBytes, field + " value mask");
    walkValues(c, t, values, active, maskBytes, field + " values");
    const std::uint64_t children = popcount(childMask, maskBytes);
    // each child needs at least its masks in the file: refuse before walking a count that cannot fit
    const std::uint64_t childMin = level == 0 ? 2 * (std::uint64_t(1) << (3 * kLog2[1])) / 8 : 64;
    if (children * childMin > c.remaining()) {
        c.fail(field + " child mask", childMaskAt,
            std::to_string(children) + " children cannot fit in the " + std::to_string(c.remaining()) +
                " bytes that remain");
    }
    for (std::size_t i = 0; i < maskBytes; ++i) {
        for (int b = 0; b < 8; ++b) {
            if (!(childMask[i] >> b & 1)) continue;
            if (level == 0) {
                ++w.internalNodes;
                walkInternal(c, t, 1, w, leafActive);
            } else {
                c.need(64, "leaf value mask", c.pos());
                leafActive.push_back(std::uint32_t(popcount(c.here(), 64)));
                c.skip(64, "leaf value mask");
                ++w.leaves;
            }
        }
    }
}

/// The grid at [@p begin, @p end): compression, metadata, transform,
/// topology and leaf buffers, as Archive::readGrid reads them.
GridWalk walkGrid(const std::string& file, const unsigned char* data, std::size_t begin, std::size_t end,
    std::uint32_t version, bool half, const std::string& grid)
{
    Cursor c(file, data, end, begin);
    GridWalk w;
    TreeShape t;
    t.version = version;
    const std::string g = "grid '" + grid + "'";
    t.compression = kCompressZip | kCompressActiveMask;
    if (version >= kNodeMaskCompression) {
        const std::size_t at = c.pos();
        t.compression = c.get<std::uint32_t>(g + " compression");
        if ((t.compression & ~(kCompressZip | kCompressActiveMask | kCompressBlosc)) != 0 ||
            ((t.compression & kCompressZip) && (t.compression & kCompressBlosc))) {
            c.fail(g + " compression", at, "unknown flags " + std::to_string(t.compression));
        }
    }
    t.storedSize = half ? 2 : 4;
    walkMetadata(c, g + " metadata", &w);

    const std::size_t mapAt = c.pos();
    const std::string map = c.string(g + " transform type", 64);
    static const std::map<std::string, std::size_t> mapSizes = {{"AffineMap", 128}, {"UnitaryMap", 128},
        {"ScaleMap", 120}, {"UniformScaleMap", 120}, {"TranslationMap", 24}, {"ScaleTranslateMap", 144},
        {"UniformScaleTranslateMap", 144}};
    const auto m = mapSizes.find(map);
    if (m == mapSizes.end())
        c.fail(g + " transform type", mapAt, "'" + printable(map) + "' is not a linear map voxhap reads");
    c.skip(m->second, g + " transform");

    const std::size_t bufAt = c.pos();
    if (c.get<std::int32_t>(g + " buffer count") != 1)
        c.fail(g + " buffer count", bufAt, "multi-buffer trees are not supported");
    c.skip(t.valueSize, g + " background");
    const std::size_t countsAt = c.pos();
    const auto tiles = c.get<std::uint32_t>(g + " root tile count");
    const auto children = c.get<std::uint32_t>(g + " root child count");
    const std::uint64_t tileBytes = 12 + t.valueSize + 1;
    const std::uint64_t childMin = 12 + 2 * 4096;
    if (std::uint64_t(tiles) * tileBytes + std::uint64_t(children) * childMin > c.remaining()) {
        c.fail(g + " root tile and child counts", countsAt,
            std::to_string(tiles) + " tiles and " + std::to_string(children) + " children cannot fit in the " +
                std::to_string(c.remaining()) + " bytes that remain");
    }
    c.skip(std::uint64_t(tiles) * tileBytes, g + " root tiles");
    std::vector<std::uint32_t> leafActive;
    std::set<std::array<std::int32_t, 3>> origins;
    for (std::uint32_t i = 0; i < children; ++i) {
        const std::size_t at = c.pos();
        std::array<std::int32_t, 3> o{};
        for (auto& x : o) x = c.get<std::int32_t>(g + " root child origin");
        if (!origins.insert(o).second) c.fail(g + " root child origin", at, "the same origin appears twice");
        ++w.rootChildren;
        walkInternal(c, t, 0, w, leafActive);
    }
    // Leaf buffers (LeafNode::readBuffers on a seekable file): the mask again, then the values.
    for (std::size_t i = 0; i < leafActive.size(); ++i) {
        c.skip(64, g + " leaf buffer mask");
        walkValues(c, t, 512, leafActive[i], 64, g + " leaf buffer " + std::to_string(i));
    }
    if (w.delayedLoadCount > w.leaves) {
        c.fail(g + " delayed-load metadata", w.delayedLoadOffset,
            std::to_string(w.delayedLoadCount) + " entries for " + std::to_string(w.leaves) + " leaves");
    }
    return w;
}

/// The grids voxhap will read, and the names of all.
struct Preflight {
    struct Grid {
        std::string name, type;
    };
    std::vector<Grid> read;
    std::vector<std::string> others; ///< names of grids left unread
};

bool hasControl(const std::string& s)
{
    return std::any_of(s.begin(), s.end(), [](char ch) { return (unsigned char)ch < 0x20 || ch == 0x7f; });
}

Preflight preflight(const std::string& file, const unsigned char* data, std::size_t size, std::uint64_t capBytes)
{
    Cursor c(file, data, size);
    c.bound(size);
    std::int64_t magic = 0;
    if (size >= sizeof(magic)) std::memcpy(&magic, data, sizeof(magic));
    if (magic != kVdbMagic) throw IoError(file + ": not a readable OpenVDB file (no OpenVDB magic number at byte 0)");
    c.skip(sizeof(magic), "magic number");
    const auto version = c.get<std::uint32_t>("file format version");
    if (version < kOldestVersion || version > kNewestVersion) {
        c.fail("file format version", 8,
            std::to_string(version) + " is not one of " + std::to_string(kOldestVersion) + " to " +
                std::to_string(kNewestVersion));
    }
    c.skip(8, "library version");
    const std::size_t offsetsAt = c.pos();
    if (c.get<std::uint8_t>("grid offsets flag") == 0) {
        c.fail("grid offsets flag", offsetsAt, "a streamed file without grid offsets is not supported");
    }
    c.skip(36, "UUID");
    walkMetadata(c, "file metadata", nullptr);

    const std::size_t countAt = c.pos();
    const auto count = c.get<std::int32_t>("grid count");
    constexpr std::uint64_t minDescriptor = 3 * 4 + 3 * 8;
    if (count < 0 || std::uint64_t(count) * minDescriptor > c.remaining()) {
        c.fail("grid count", countAt,
            std::to_string(count) + " grids cannot fit in the " + std::to_string(c.remaining()) + " bytes that remain");
    }
    Preflight p;
    std::set<std::string> names;    // of the grids read
    std::multiset<std::string> all; // of every grid
    std::uint64_t memory = 0;
    for (std::int32_t i = 0; i < count; ++i) {
        const std::string d = "grid descriptor " + std::to_string(i);
        const std::size_t at = c.pos();
        const std::string unique = c.string(d + " name", 1u << 16);
        std::string type = c.string(d + " type", 256);
        const std::string parent = c.string(d + " instance parent", 1u << 16);
        const std::size_t posAt = c.pos();
        const auto gridPos = c.get<std::int64_t>(d + " grid position");
        const auto blockPos = c.get<std::int64_t>(d + " block position");
        const auto endPos = c.get<std::int64_t>(d + " end position");
        if (gridPos < std::int64_t(c.pos()) || blockPos < gridPos || endPos < blockPos ||
            std::uint64_t(endPos) > size) {
            c.fail(d + " positions", posAt,
                "grid " + std::to_string(gridPos) + ", block " + std::to_string(blockPos) + ", end " +
                    std::to_string(endPos) + " are not in order inside the " + std::to_string(size) + "-byte file");
        }
        const std::string name = unique.substr(0, unique.find('\x1e')); // GridDescriptor::stripSuffix
        if (hasControl(name)) c.fail(d + " name", at, "the grid name holds a control character");
        all.insert(name);
        const std::string halfSuffix = "_HalfFloat";
        const bool half = type.size() > halfSuffix.size() &&
            type.compare(type.size() - halfSuffix.size(), halfSuffix.size(), halfSuffix) == 0;
        if (half) type.resize(type.size() - halfSuffix.size());
        const bool channel = name == "hu" || name == "t1" || name == "label" || name == "intensity";
        const bool wanted = type == "Tree_float_5_4_3" || (channel && type == "Tree_int32_5_4_3");
        if (channel && !wanted) {
            c.fail(
                d + " type", at, "grid '" + name + "' has type '" + printable(type) + "', not a float or int32 grid");
        }
        if (wanted) {
            if (!parent.empty())
                c.fail(d + " instance parent", at,
                    "grid '" + name + "' is an instance of another grid, which voxhap does not read");
            if (half && type != "Tree_float_5_4_3")
                c.fail(d + " type", at, "half-float storage on a grid that is not float");
            if (!names.insert(name).second) c.fail(d + " name", at, "grid '" + name + "' appears twice");
            const GridWalk w = walkGrid(file, data, std::size_t(gridPos), std::size_t(endPos), version, half, name);
            using Root = openvdb::FloatTree::RootNodeType;
            using Upper = Root::ChildNodeType;
            using Lower = Upper::ChildNodeType;
            using Leaf = Lower::ChildNodeType;
            memory += w.rootChildren * (sizeof(Upper) + 64) + w.internalNodes * sizeof(Lower) +
                w.leaves * (sizeof(Leaf) + Leaf::SIZE * sizeof(float));
            if (memory > capBytes) {
                throw IoError(file + ": grid '" + name + "' brings the trees to " + mib(memory) +
                    " of memory, over the memory cap of " + mib(capBytes) + " (--memory-cap)");
            }
            p.read.push_back({name, type});
        } else {
            p.others.push_back(name);
        }
        c = Cursor(file, data, size, std::size_t(endPos)); // GridDescriptor::seekToEnd
        c.bound(size);
    }
    // OpenVDB finds a grid by name: a grid read must be the only one of its name.
    for (const auto& g : p.read) {
        if (all.count(g.name) > 1) throw IoError(file + ": grid '" + g.name + "' appears twice");
    }
    return p;
}

/// A read-only mapping of a whole file.
class MappedFile {
public:
    explicit MappedFile(const std::filesystem::path& file)
    {
        const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd < 0) throw IoError(file.string() + ": cannot open (" + std::strerror(errno) + ")");
        struct stat st { };
        if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
            ::close(fd);
            throw IoError(file.string() + ": not a regular file");
        }
        mSize = std::size_t(st.st_size);
        if (mSize > 0) {
            void* p = ::mmap(nullptr, mSize, PROT_READ, MAP_PRIVATE, fd, 0);
            if (p == MAP_FAILED) {
                ::close(fd);
                throw IoError(file.string() + ": cannot map (" + std::strerror(errno) + ")");
            }
            mData = static_cast<const unsigned char*>(p);
        }
        ::close(fd);
    }
    ~MappedFile()
    {
        if (mData) ::munmap(const_cast<unsigned char*>(mData), mSize);
    }
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;
    const unsigned char* data() const { return mData; }
    std::size_t size() const { return mSize; }

private:
    const unsigned char* mData = nullptr;
    std::size_t mSize = 0;
};

} // namespace vdbwalk
} // namespace

void saveVdb(const Volume& v, const std::filesystem::path& file)
{
    initializeOpenVdb();
    openvdb::GridCPtrVec grids;
    for (Channel c : kChannels) {
        if (v.has(c)) grids.push_back(v.grid(c));
    }
    for (const auto& [name, g] : v.derivedGrids()) grids.push_back(g);
    if (grids.empty()) throw IoError(file.string() + ": the volume holds no grid to save");

    openvdb::MetaMap meta;
    meta.insertMeta(kFormatKey, openvdb::Int32Metadata(kFormatVersion));
    const auto& md = v.metadata();
    putString(meta, "source", md.source);
    putString(meta, "description", md.description);
    putString(meta, "hu_units", md.huUnits);
    putString(meta, "t1_units", md.t1Units);
    putString(meta, "intensity_units", md.intensityUnits);
    for (const auto& [name, text] : metadataFacts(md)) putString(meta, name, text);
    for (const auto& [key, value] : md.extra) putString(meta, "extra." + key, value);
    meta.insertMeta("voxhap.index_min", openvdb::Vec3IMetadata(openvdb::Vec3i(v.indexBox().min.data())));
    meta.insertMeta("voxhap.index_max", openvdb::Vec3IMetadata(openvdb::Vec3i(v.indexBox().max.data())));

    writeAtomically(file, [&](const std::filesystem::path& tmp) {
        openvdb::io::File out(tmp.string());
        out.write(grids, meta);
        out.close();
    });
}

Volume loadVdb(const std::filesystem::path& file, std::uint64_t memoryCapBytes)
{
    initializeOpenVdb();
    if (!std::filesystem::is_regular_file(file)) throw IoError(file.string() + ": no such file");
    vdbwalk::Preflight plan;
    {
        const vdbwalk::MappedFile mapped(file);
        plan = vdbwalk::preflight(file.string(), mapped.data(), mapped.size(), memoryCapBytes);
    }
    openvdb::io::File in(file.string());
    openvdb::GridPtrVec gridList;
    auto grids = &gridList;
    openvdb::MetaMap::Ptr meta;
    try {
        in.open(false); // no delayed loading: the file may change or vanish afterwards
        for (const auto& g : plan.read) gridList.push_back(in.readGrid(g.name));
        meta = in.getMetadata();
        in.close();
    } catch (const openvdb::Exception& e) {
        throw IoError(file.string() + ": not a readable OpenVDB file (" + oneLineMessage(e.what()) + ")");
    } catch (const std::exception& e) {
        throw IoError(file.string() + ": cannot read (" + oneLineMessage(e.what()) + ")");
    }

    std::array<openvdb::GridBase::Ptr, kChannels.size()> byChannel{};
    std::vector<openvdb::GridBase::Ptr> derived; // float grids besides the channels, e.g. distance fields
    std::string others;
    for (const auto& name : plan.others) others += (others.empty() ? "" : ", ") + name;
    for (const auto& g : *grids) {
        bool matched = false;
        for (Channel c : kChannels) {
            if (g->getName() != channelName(c)) continue;
            if (byChannel[std::size_t(c)]) throw IoError(file.string() + ": grid '" + g->getName() + "' appears twice");
            byChannel[std::size_t(c)] = g;
            matched = true;
        }
        if (matched) continue;
        others += (others.empty() ? "" : ", ") + g->getName();
        if (g->isType<FloatGrid>()) derived.push_back(g);
    }
    openvdb::GridBase::Ptr first;
    for (const auto& g : byChannel) {
        if (g && !first) first = g;
    }
    if (!first) {
        throw IoError(file.string() + ": no grid named hu, t1, label or intensity" +
            (others.empty() ? "" : " (found: " + others + ")"));
    }
    for (const auto& g : byChannel) {
        if (g && g->transform() != first->transform()) {
            throw IoError(file.string() + ": grid '" + g->getName() + "' has a different transform from '" +
                first->getName() + "'");
        }
    }
    if (!first->transform().isLinear())
        throw IoError(file.string() + ": grid '" + first->getName() + "' has a non-linear transform");

    IndexBox box;
    auto lo = meta->getMetadata<openvdb::Vec3IMetadata>("voxhap.index_min");
    auto hi = meta->getMetadata<openvdb::Vec3IMetadata>("voxhap.index_max");
    if (lo && hi) {
        box.min = Vec3i(lo->value().x(), lo->value().y(), lo->value().z());
        box.max = Vec3i(hi->value().x(), hi->value().y(), hi->value().z());
    } else { // a foreign file: the union of the active bounding boxes
        openvdb::CoordBBox bb;
        for (const auto& g : byChannel) {
            if (g) bb.expand(g->evalActiveVoxelBoundingBox());
        }
        box.min = fromCoord(bb.min());
        box.max = fromCoord(bb.max());
    }

    Volume v(first->transform().copy(), box);
    for (Channel c : kChannels) {
        if (auto& g = byChannel[std::size_t(c)]) {
            try {
                v.setGrid(c, g);
            } catch (const ValueError& e) {
                throw IoError(file.string() + ": " + e.what());
            }
        }
    }
    for (const auto& g : derived) {
        if (g->transform() != first->transform()) {
            throw IoError(file.string() + ": grid '" + g->getName() + "' has a different transform from '" +
                first->getName() + "'");
        }
        if (v.derived(g->getName())) throw IoError(file.string() + ": grid '" + g->getName() + "' appears twice");
        v.setDerived(g->getName(), g);
    }
    auto& md = v.metadata();
    md.source = getString(*meta, "source", file.filename().string());
    md.description = getString(*meta, "description");
    md.huUnits = getString(*meta, "hu_units", "HU");
    md.t1Units = getString(*meta, "t1_units", "ms");
    md.intensityUnits = getString(*meta, "intensity_units", "arbitrary units");
    // The typed facts under their own names ("voxhap.field_strength"), the
    // display notes under "voxhap.extra.<key>"; a file written before a fact
    // was typed holds it among the notes, and is read the same.
    const std::string extraPrefix = std::string(kPrefix) + "extra.";
    try {
        for (auto it = meta->beginMeta(); it != meta->endMeta(); ++it) {
            const auto s = meta->getMetadata<openvdb::StringMetadata>(it->first);
            if (!s || it->first.rfind(kPrefix, 0) != 0) continue;
            if (it->first.rfind(extraPrefix, 0) == 0) {
                md.extra[it->first.substr(extraPrefix.size())] = s->value();
            } else {
                setMetadataFact(
                    md, std::string_view(it->first).substr(std::strlen(kPrefix)), s->value(), file.string());
            }
        }
        upgradeLegacyExtras(md, file.string());
    } catch (const ValueError& e) {
        throw IoError(e.what());
    }
    return v;
}

} // namespace voxhap::volume
