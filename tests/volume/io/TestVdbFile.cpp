// SPDX-License-Identifier: Apache-2.0
/// @file TestVdbFile.cpp
/// @brief .vdb round trips are exact; bad files give one clear error.

#include "common/Tolerances.h"

#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/phantoms/Phantoms.h"
#include "volume/io/VdbFile.h"

#include <Eigen/Geometry>
#include <openvdb/io/File.h>

#include <filesystem>
#include <fstream>
#include <unistd.h> // for getpid: per-process temp names

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

} // namespace
} // namespace voxhap::volume
