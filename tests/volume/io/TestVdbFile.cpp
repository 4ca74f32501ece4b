// SPDX-License-Identifier: Apache-2.0
/// @file TestVdbFile.cpp
/// @brief .vdb round trips are exact; bad files give one clear error.

#include "common/Tolerances.h"

#include "core/Errors.h"
#include "phantoms/Phantoms.h"
#include "volume/Grids.h"
#include "volume/io/VdbFile.h"

#include <Eigen/Geometry>
#include <openvdb/io/File.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h> // for getpid: per-process temp names, fork

namespace voxhap::volume {
namespace {

namespace fs = std::filesystem;

/// A fresh directory under the system temp dir, removed at the end of the test.
class TempDir {
public:
    TempDir()
    {
        mPath = fs::temp_directory_path() /
            ("voxhap-test-" + std::to_string(::getpid()) + "-" +
                testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(mPath);
    }
    ~TempDir() { fs::remove_all(mPath); }
    fs::path operator/(const std::string& name) const { return mPath / name; }
    const fs::path& path() const { return mPath; }

private:
    fs::path mPath;
};

template <typename GridT> void expectSameVoxels(const GridT& a, const GridT& b)
{
    EXPECT_EQ(a.activeVoxelCount(), b.activeVoxelCount());
    EXPECT_EQ(a.background(), b.background());
    EXPECT_TRUE(a.tree().hasSameTopology(b.tree()));
    auto acc = b.getConstAccessor();
    for (auto it = a.cbeginValueOn(); it; ++it) {
        if (it.isVoxelValue()) {
            ASSERT_EQ(*it, acc.getValue(it.getCoord()));
        } else { // a tile: compare its value at its first voxel, where b must hold the same
            ASSERT_EQ(*it, acc.getValue(it.getCoord()));
        }
    }
}

TEST(VdbFile, RoundTripIsExact)
{
    TempDir dir;
    LumbarParams p;
    p.grid.spacing = Vec3d(0.7, 0.5, 1.1);
    p.grid.direction = Eigen::AngleAxisd(0.2, Vec3d(0, 0, 1)).toRotationMatrix();
    Volume v = makePhantom(lumbarModel(p, TissueTable::builtin()), p.grid, TissueTable::builtin());
    v.metadata().description = "round trip ✓ with UTF-8";
    v.metadata().extra["note"] = "kept";
    saveVdb(v, dir / "v.vdb");
    const Volume back = loadVdb(dir / "v.vdb");

    EXPECT_EQ(back.indexBox(), v.indexBox());
    EXPECT_TRUE(back.transform() == v.transform());
    EXPECT_EQ(back.metadata(), v.metadata());
    expectSameVoxels(*huGrid(v), *huGrid(back));
    expectSameVoxels(*t1Grid(v), *t1Grid(back));
    expectSameVoxels(*labelGrid(v), *labelGrid(back));
    // All grids share the one transform object after loading.
    EXPECT_EQ(&back.grid(Channel::Hu)->transform(), &back.grid(Channel::Label)->transform());
    EXPECT_EQ(fs::directory_iterator(dir.path()) == fs::directory_iterator(), false);
    for (const auto& e : fs::directory_iterator(dir.path())) EXPECT_EQ(e.path().filename(), "v.vdb") << "stray file";
}

TEST(VdbFile, SubsetOfChannelsRoundTrips)
{
    TempDir dir;
    Volume v = makePhantom(slabModel(SlabParams{}, TissueTable::builtin()), GridSpec{}, TissueTable::builtin());
    v.removeGrid(Channel::T1);
    v.removeGrid(Channel::Label);
    saveVdb(v, dir / "hu.vdb");
    const Volume back = loadVdb(dir / "hu.vdb");
    EXPECT_TRUE(back.has(Channel::Hu));
    EXPECT_FALSE(back.has(Channel::T1));
    EXPECT_FALSE(back.has(Channel::Label));
    expectSameVoxels(*huGrid(v), *huGrid(back));
}

void expectIoError(const fs::path& file, const std::string& fragment)
{
    try {
        loadVdb(file);
        ADD_FAILURE() << "loaded " << file;
    } catch (const IoError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(file.string()), std::string::npos) << msg;
        EXPECT_NE(msg.find(fragment), std::string::npos) << msg;
    }
}

TEST(VdbFile, BadFilesGiveOneClearError)
{
    TempDir dir;
    expectIoError(dir / "missing.vdb", "no such file");
    {
        std::ofstream(dir / "text.vdb") << "this is not a vdb file";
    }
    expectIoError(dir / "text.vdb", "not a readable OpenVDB file");
    // A valid .vdb whose grids are not voxhap channels.
    initializeOpenVdb();
    auto density = FloatGrid::create(0.0f);
    density->setName("density");
    openvdb::io::File((dir / "foreign.vdb").string()).write({density});
    expectIoError(dir / "foreign.vdb", "found: density");
}

// ---------------------------------------------------------------------------
// Hostile lengths (issue 20 item 1): refused before OpenVDB allocates from them.

std::vector<char> readBytes(const fs::path& file)
{
    std::ifstream in(file, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const fs::path& file, const std::vector<char>& bytes)
{
    std::ofstream(file, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
}

/// Offset of the first @p what in @p bytes (a test failure when absent).
std::size_t find(const std::vector<char>& bytes, const std::string& what)
{
    const auto it = std::search(bytes.begin(), bytes.end(), what.begin(), what.end());
    EXPECT_NE(it, bytes.end()) << what;
    return std::size_t(it - bytes.begin());
}

template <typename T> void put(std::vector<char>& bytes, std::size_t at, T value)
{
    ASSERT_LE(at + sizeof(T), bytes.size());
    std::memcpy(bytes.data() + at, &value, sizeof(T));
}

/// A small voxhap .vdb (a slab phantom at 2 mm) as bytes.
std::vector<char> smallVdb(const TempDir& dir)
{
    SlabParams p;
    GridSpec g;
    g.spacing = Vec3d(2, 2, 2);
    const Volume v = makePhantom(slabModel(p, TissueTable::builtin()), g, TissueTable::builtin());
    saveVdb(v, dir / "small.vdb");
    return readBytes(dir / "small.vdb");
}

/// Address space of this process now [bytes].
std::uint64_t addressSpace()
{
    std::ifstream statm("/proc/self/statm");
    std::uint64_t pages = 0;
    statm >> pages;
    return pages * std::uint64_t(::sysconf(_SC_PAGESIZE));
}

/// Exit codes of the bounded child.
enum : int {
    kRefused = 0,
    kLoaded = 1,
    kOutOfMemory = 2,
    kOther = 3,
    kWrongMessage = 4
};

/// CPU seconds a child may use (RLIMIT_CPU): a refusal of a small file reads a
/// few hundred bytes and takes milliseconds; a parser that walks a hostile length
/// byte by byte, or loops, runs out and is killed (SIGXCPU), which fails the
/// test. CPU time, not the wall clock, so a loaded machine does not fail it.
constexpr rlim_t kRefusalCpuS = 5;
/// OpenVDB alone on the same file may work a while before it runs out of memory.
constexpr rlim_t kUnboundedCpuS = 60;

/// Load @p file in a forked child whose address space may grow by 1 GiB at
/// most (RLIMIT_AS) and that may use @p cpuSeconds of CPU (RLIMIT_CPU): the
/// child's exit code says what happened (128 + the signal that killed it).
template <typename Load>
int loadBounded(const fs::path& file, const std::string& fragment, Load load, rlim_t cpuSeconds = kRefusalCpuS)
{
    const pid_t pid = ::fork();
    if (pid == 0) {
        const rlim_t limit = rlim_t(addressSpace() + (std::uint64_t(1) << 30));
        const rlimit rl{limit, limit};
        ::setrlimit(RLIMIT_AS, &rl);
        const rlimit cpu{cpuSeconds, cpuSeconds + 1}; // SIGXCPU at the soft limit, SIGKILL a second later
        ::setrlimit(RLIMIT_CPU, &cpu);
        int code = kOther;
        try {
            load(file);
            code = kLoaded;
        } catch (const IoError& e) {
            const std::string msg = e.what();
            const bool ok = msg.rfind(file.string() + ": ", 0) == 0 && msg.find('\n') == std::string::npos &&
                msg.find(fragment) != std::string::npos;
            if (!ok) std::fprintf(stderr, "unexpected refusal: %s\n", msg.c_str());
            code = ok ? kRefused : kWrongMessage;
        } catch (const std::bad_alloc&) {
            code = kOutOfMemory;
        } catch (...) {
            code = kOther;
        }
        std::fflush(stderr);
        ::_exit(code);
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

int loadVdbBounded(const fs::path& file, const std::string& fragment)
{
    return loadBounded(file, fragment, [](const fs::path& f) { loadVdb(f); });
}

TEST(VdbFile, SixteenFfBytesOverAMetadataLengthAreRefusedWithinOneGiB)
{
    // The fault as first seen: 16 bytes 0xFF at offset 200, where the files of
    // the time had the second metadata entry's last value byte and the third's
    // name length. The same place in today's layout: before the third entry's name.
    TempDir dir;
    std::vector<char> bytes = smallVdb(dir);
    const std::size_t at = find(bytes, "voxhap.field_strength_source") - 4 - 1;
    ASSERT_GT(bytes.size(), at + 16);
    std::fill_n(bytes.begin() + std::ptrdiff_t(at), 16, char(0xFF));
    writeBytes(dir / "ff.vdb", bytes);
    // Refused within 1 GiB and kRefusalCpuS of CPU (a child over either does not exit kRefused).
    EXPECT_EQ(loadVdbBounded(dir / "ff.vdb", "at byte "), kRefused);
    // The bound is real: OpenVDB alone, given the same file, asks for more (the issue saw 9 GB).
    const int raw = loadBounded(
        dir / "ff.vdb", "",
        [](const fs::path& f) {
            openvdb::io::File in(f.string());
            in.open(false);
            in.getGrids();
        },
        kUnboundedCpuS);
    EXPECT_TRUE(raw == kOutOfMemory || raw >= 128) << "OpenVDB alone: exit " << raw;
    // The CPU limit is real: a load that never ends is killed by it.
    const int spin = loadBounded(
        dir / "ff.vdb", "",
        [](const fs::path&) {
            volatile unsigned long i = 0;
            for (;;) i = i + 1;
        },
        1);
    EXPECT_EQ(spin, 128 + SIGXCPU);
}

struct Corruption {
    std::string name;  ///< what is changed
    std::string field; ///< what the refusal must name
    std::function<void(std::vector<char>&)> apply;
};

TEST(VdbFile, HostileLengthsAreRefusedNamingFieldAndOffsetWithinOneGiB)
{
    TempDir dir;
    const std::vector<char> good = smallVdb(dir);
    const std::size_t metaCount = 8 + 4 + 8 + 1 + 36; // after magic, version, library version, flag, UUID
    const std::vector<Corruption> cases = {
        {"file metadata count", "file metadata count at byte 57",
            [&](auto& b) { put<std::uint32_t>(b, metaCount, 0xFFFFFFFFu); }},
        {"first metadata name length", "file metadata entry 0 name length at byte 61",
            [&](auto& b) { put<std::uint32_t>(b, metaCount + 4, 0x7FFFFFF0u); }},
        {"string metadata value length", "value",
            [&](auto& b) { put<std::uint32_t>(b, find(b, "string") + 6, 0x7FFFFFF0u); }},
        {"grid type length", "grid descriptor",
            [&](auto& b) { put<std::uint32_t>(b, find(b, "Tree_float_5_4_3") - 4, 0xFFFFFF00u); }},
        {"grid end position", "positions",
            [&](auto& b) {
                const std::size_t type = find(b, "Tree_float_5_4_3");
                put<std::int64_t>(b, type + 16 + 4 + 16, std::int64_t(1) << 40); // after the empty parent name
            }},
        {"delayed-load entry count", "delayed-load",
            [&](auto& b) { put<std::uint32_t>(b, find(b, "__delayedload") + 13 + 4, 0x0FFFFFFFu); }},
        {"transform type length", "transform type length",
            [&](auto& b) { put<std::uint32_t>(b, find(b, "UniformScaleTranslateMap") - 4, 0xFFFFFFF0u); }},
        {"root child count", "root tile and child counts",
            [&](auto& b) {
                // UniformScaleTranslateMap (144 bytes), buffer count, background, tile count, child count
                const std::size_t mapEnd = find(b, "UniformScaleTranslateMap") + 24 + 144;
                put<std::uint32_t>(b, mapEnd + 4 + 4 + 4, 0x00FFFFFFu);
            }},
    };
    for (const auto& c : cases) {
        SCOPED_TRACE(c.name);
        std::vector<char> bytes = good;
        c.apply(bytes);
        ASSERT_NE(bytes, good);
        const fs::path file = dir / "bad.vdb";
        writeBytes(file, bytes);
        EXPECT_EQ(loadVdbBounded(file, c.field), kRefused);
        try {
            loadVdb(file);
            ADD_FAILURE() << "loaded";
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find("at byte "), std::string::npos) << e.what();
        }
    }
}

TEST(VdbFile, EveryTruncationIsRefused)
{
    TempDir dir;
    const std::vector<char> good = smallVdb(dir);
    for (std::size_t n = 0; n < good.size(); n += std::max<std::size_t>(1, good.size() / 97)) {
        writeBytes(dir / "cut.vdb", std::vector<char>(good.begin(), good.begin() + std::ptrdiff_t(n)));
        EXPECT_THROW(loadVdb(dir / "cut.vdb"), IoError) << n << " bytes";
    }
}

TEST(VdbFile, MemoryCapRefusesLargeTreesBeforeReading)
{
    TempDir dir;
    smallVdb(dir);
    const fs::path file = dir / "small.vdb";
    try {
        loadVdb(file, std::uint64_t(1) << 16);
        ADD_FAILURE() << "loaded over the cap";
    } catch (const IoError& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.rfind(file.string() + ": ", 0), 0u) << msg;
        EXPECT_NE(msg.find("memory cap of 1 MiB"), std::string::npos) << msg;
        EXPECT_NE(msg.find("--memory-cap"), std::string::npos) << msg;
    }
    EXPECT_NO_THROW(loadVdb(file, std::uint64_t(64) << 20));
}

TEST(VdbFile, ValidFileLoadsTheSameAfterTheWalk)
{
    TempDir dir;
    LumbarParams p;
    p.grid.spacing = Vec3d(1, 1, 1);
    Volume v = makePhantom(lumbarModel(p, TissueTable::builtin()), p.grid, TissueTable::builtin());
    saveVdb(v, dir / "v.vdb");
    initializeOpenVdb();
    openvdb::io::File raw((dir / "v.vdb").string());
    raw.open(false);
    const auto rawHu = openvdb::gridPtrCast<FloatGrid>(raw.readGrid("hu"));
    raw.close();
    const Volume back = loadVdb(dir / "v.vdb");
    expectSameVoxels(*rawHu, *huGrid(back));
    expectSameVoxels(*huGrid(v), *huGrid(back));
    expectSameVoxels(*labelGrid(v), *labelGrid(back));
}

TEST(VdbFile, TypedFactsAreSavedUnderTheirOwnKeys)
{
    TempDir dir;
    LumbarParams p;
    p.grid.field = FieldStrength::T3;
    Volume v = makePhantom(lumbarModel(p, TissueTable::builtin()), p.grid, TissueTable::builtin());
    saveVdb(v, dir / "v.vdb");
    openvdb::io::File f((dir / "v.vdb").string());
    f.open(false);
    const auto meta = f.getMetadata();
    f.close();
    const auto text = [&meta](const std::string& key) {
        const auto m = meta->getMetadata<openvdb::StringMetadata>(key);
        return m ? m->value() : std::string("(absent)");
    };
    EXPECT_EQ(text("voxhap.field_strength"), "3T");
    EXPECT_EQ(text("voxhap.field_strength_source"), "generator");
    EXPECT_EQ(text("voxhap.modality"), "phantom");
    EXPECT_NE(text("voxhap.landmarks").find("\"epidural_target\""), std::string::npos);
    EXPECT_NE(text("voxhap.layers").find("\"ligamentum_flavum\""), std::string::npos);
    EXPECT_EQ(text("voxhap.extra.field_strength"), "(absent)"); // not among the display notes any more
}

TEST(VdbFile, FilesWrittenWithTheFactsAsExtrasStayReadable)
{
    // A .vdb as voxhap wrote it before the facts were typed: a phantom's field
    // strength, layers and landmarks, an MR's T1 kind, modality source and 4D
    // choice, all under "voxhap.extra.<key>"; mr_weighting "" for a phantom.
    TempDir dir;
    LumbarParams p;
    p.grid.field = FieldStrength::T3;
    const Volume made = makePhantom(lumbarModel(p, TissueTable::builtin()), p.grid, TissueTable::builtin());
    const auto write = [&](const fs::path& file, const std::map<std::string, std::string>& keys) {
        openvdb::MetaMap meta;
        meta.insertMeta("voxhap.format", openvdb::Int32Metadata(1));
        for (const auto& [k, value] : keys) meta.insertMeta(k, openvdb::StringMetadata(value));
        meta.insertMeta("voxhap.index_min", openvdb::Vec3IMetadata(openvdb::Vec3i(made.indexBox().min.data())));
        meta.insertMeta("voxhap.index_max", openvdb::Vec3IMetadata(openvdb::Vec3i(made.indexBox().max.data())));
        openvdb::io::File out(file.string());
        out.write(
            openvdb::GridCPtrVec{made.grid(Channel::Hu), made.grid(Channel::T1), made.grid(Channel::Label)}, meta);
        out.close();
    };
    const std::string layers = R"({"entry": [0, 0, 0], "direction": [0, -1, 0], "layers": [)"
                               R"({"tissue": "skin", "id": 1, "start_mm": 0, "end_mm": 2}]})";
    write(dir / "old.vdb",
        {{"voxhap.modality", "phantom"}, {"voxhap.mr_weighting", ""}, {"voxhap.source", "voxhap phantom lumbar"},
            {"voxhap.extra.field_strength", "3T"}, {"voxhap.extra.layers", layers},
            {"voxhap.extra.landmarks", R"({"lesion": [1.5, -60, 0.25]})"}, {"voxhap.extra.t1_kind", "T1 map"},
            {"voxhap.extra.volume", "2 of 13 (b=1000)"},
            {"voxhap.extra.modality_source", "inferred from the data: air at -1000"}, {"voxhap.extra.note", "kept"}});
    const Volume old = loadVdb(dir / "old.vdb");
    const VolumeMetadata& md = old.metadata();
    EXPECT_EQ(md.modality, "phantom");
    EXPECT_EQ(md.mrWeighting, std::nullopt);
    EXPECT_EQ(md.fieldStrength, FieldStrength::T3);
    EXPECT_EQ(md.fieldStrengthSource, FactSource::Generator);
    EXPECT_EQ(md.t1Kind, T1Kind::Map);
    EXPECT_EQ(md.modalitySource, FactSource::Data);
    EXPECT_EQ(md.volumeChoice, (VolumeChoice{2, 13, "b=1000"}));
    ASSERT_TRUE(md.phantomLayers);
    ASSERT_EQ(md.phantomLayers->layers.size(), 1u);
    EXPECT_EQ(md.phantomLayers->layers[0].name, "skin");
    EXPECT_EQ(md.phantomLayers->layers[0].endMm, 2.0);
    EXPECT_EQ(phantomLandmark(old, "lesion"), Vec3d(1.5, -60, 0.25));
    EXPECT_EQ(md.extra, (std::map<std::string, std::string>{{"note", "kept"}}));
    // Saved again, it is saved the new way and reads back the same.
    saveVdb(old, dir / "again.vdb");
    EXPECT_EQ(loadVdb(dir / "again.vdb").metadata(), md);

    // A malformed old value is refused in one line naming the file and the key.
    write(dir / "bad.vdb", {{"voxhap.extra.layers", "{not json"}});
    expectIoError(dir / "bad.vdb", "metadata 'layers'");
    write(dir / "bad-field.vdb", {{"voxhap.field_strength", "7T"}});
    expectIoError(dir / "bad-field.vdb", "metadata 'field_strength'");
}

TEST(VdbFile, FailedWriteLeavesNothingBehind)
{
    TempDir dir;
    const Volume v = makePhantom(slabModel(SlabParams{}, TissueTable::builtin()), GridSpec{}, TissueTable::builtin());
    EXPECT_THROW(saveVdb(v, dir / "no-such-dir" / "v.vdb"), IoError);
    EXPECT_FALSE(fs::exists(dir / "no-such-dir"));
    Volume empty(Geometry{}, IndexBox{});
    EXPECT_THROW(saveVdb(empty, dir / "empty.vdb"), IoError);
    EXPECT_TRUE(fs::is_empty(dir.path()));
}

TEST(Volume, SetGridChecksTypeAndBackground)
{
    initializeOpenVdb();
    Volume v(Geometry{}, IndexBox{});
    EXPECT_THROW(v.setGrid(Channel::Label, FloatGrid::create(0.0f)), ValueError);
    EXPECT_THROW(v.setGrid(Channel::Hu, FloatGrid::create(0.0f)), ValueError); // air is -1000 HU
    EXPECT_THROW(v.setGrid(Channel::Hu, LabelGrid::create(0)), ValueError);
    v.setGrid(Channel::Hu, FloatGrid::create(kAirHu));
    EXPECT_EQ(v.grid(Channel::Hu)->getName(), "hu");
}

// OpenVDB's delayed-load table holds a byte per leaf; a table shorter than
// Blosc's pad length (128 bytes) is padded before it is compressed, and one
// shorter than 48 bytes is stored raw. Grids of 1 to 200 leaves cover the
// three cases: each file voxhap writes must load again, voxel for voxel (the
// walk once refused the padded tables, "Blosc header declares 128 bytes,
// expected 64").
TEST(VdbFile, GridsOfFewLeavesLoadWhateverTheirDelayedLoadTableLength)
{
    TempDir dir;
    initializeOpenVdb();
    for (int leaves : {1, 47, 48, 64, 127, 128, 200}) {
        auto grid = FloatGrid::create(kAirHu);
        for (int n = 0; n < leaves; ++n) grid->tree().setValueOn(openvdb::Coord(16 * n, 0, 0), 40.0f);
        ASSERT_EQ(grid->tree().leafCount(), openvdb::Index32(leaves));
        Volume v(Geometry{}, IndexBox{Vec3i::Zero(), Vec3i(16 * leaves, 0, 0)});
        v.setGrid(Channel::Hu, grid);
        const fs::path file = dir / ("leaves-" + std::to_string(leaves) + ".vdb");
        saveVdb(v, file);
        SCOPED_TRACE(std::to_string(leaves) + " leaves");
        const Volume back = loadVdb(file);
        expectSameVoxels(*grid, *huGrid(back));
    }
}

} // namespace
} // namespace voxhap::volume
