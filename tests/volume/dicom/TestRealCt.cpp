// SPDX-License-Identifier: Apache-2.0
/// @file TestRealCt.cpp
/// @brief The real abdominal CT in ../shared/data/ct-abdomen-tcia/dicom:
/// size, spacing, origin and orientation against its headers (read here
/// through GDCM, apart from the reader), exact HU, anatomy (spine posterior
/// and midline, reads as bone). Skipped, with a message, where the data is absent.

#include "common/SharedData.h"
#include "common/Tolerances.h"

#include "common/DicomNative.h"
#include "volume/Grids.h"
#include "volume/dicom/DicomSeries.h"

#include <gdcmImageReader.h>
#include <gtest/gtest.h>
#include <openvdb/tools/Statistics.h>

#include <cstring>
#include <filesystem>
#include <memory>
#include <set>

namespace {

namespace fs = std::filesystem;
using voxhap::Vec3d;
using namespace voxhap::volume;

const fs::path kCtDir = voxhap::test::realCtDir();

using voxhap::test::kDicomDecimalMm;

class RealCt : public testing::Test {
protected:
    static void SetUpTestSuite()
    {
        if (!fs::is_directory(kCtDir)) return;
        sReport = std::make_unique<DicomLoadReport>();
        sVolume = std::make_unique<Volume>(loadDicom({kCtDir}, {}, sReport.get()));
    }
    static void TearDownTestSuite()
    {
        sVolume.reset();
        sReport.reset();
    }
    void SetUp() override
    {
        VOXHAP_REQUIRE_DIR(kCtDir);
        ASSERT_TRUE(sVolume) << "the real CT did not load";
    }
    /// One file through GDCM's image reader: origin and rescaled pixels.
    struct Slice {
        Vec3d origin;
        std::vector<double> hu;
        unsigned columns = 0, rows = 0;
    };
    static Slice readDirectly(const fs::path& file)
    {
        gdcm::ImageReader r;
        r.SetFileName(file.string().c_str());
        EXPECT_TRUE(r.Read()) << file;
        const gdcm::Image& img = r.GetImage();
        Slice s;
        s.origin = Vec3d(img.GetOrigin(0), img.GetOrigin(1), img.GetOrigin(2));
        s.columns = img.GetDimension(0);
        s.rows = img.GetDimension(1);
        EXPECT_EQ(img.GetPixelFormat().GetScalarType(), gdcm::PixelFormat::UINT16) << "the README: uncompressed 16-bit";
        std::vector<std::uint16_t> raw(std::size_t(s.columns) * s.rows);
        EXPECT_EQ(img.GetBufferLength(), raw.size() * 2);
        img.GetBuffer(reinterpret_cast<char*>(raw.data()));
        for (auto v : raw) s.hu.push_back(img.GetSlope() * v + img.GetIntercept());
        return s;
    }
    static std::unique_ptr<Volume> sVolume;
    static std::unique_ptr<DicomLoadReport> sReport;
};
std::unique_ptr<Volume> RealCt::sVolume;
std::unique_ptr<DicomLoadReport> RealCt::sReport;

TEST_F(RealCt, SizeSpacingAndOriginMatchTheHeaders)
{
    // Values from the headers (gdcmdump): Rows = Columns = 512, PixelSpacing
    // 1.07421875\1.07421875, 134 files at z = 85.91 .. 484.91 in steps of 3.
    EXPECT_EQ(sVolume->indexBox().dims(), voxhap::Vec3i(512, 512, 134));
    const Geometry g = sVolume->geometry();
    EXPECT_TRUE(voxhap::test::nearVec(g.spacing, Vec3d(1.07421875, 1.07421875, 3.0), kDicomDecimalMm));
    EXPECT_TRUE(voxhap::test::nearVec(g.origin, Vec3d(-275.0, -178.1, 85.91), kDicomDecimalMm));
    EXPECT_EQ(sVolume->metadata().modality, "CT");
    EXPECT_FALSE(sReport->resampled);
}

TEST_F(RealCt, PatientLeftIsPlusXPosteriorPlusYSuperiorPlusZ)
{
    // ImageOrientationPatient 1\0\0\0\1\0: columns run to the patient's left
    // (+x in LPS), rows to posterior (+y); the slice order follows +z (superior).
    const Geometry g = sVolume->geometry();
    EXPECT_TRUE(voxhap::test::nearVec(g.direction.col(0), Vec3d::UnitX(), kDicomDecimalMm));
    EXPECT_TRUE(voxhap::test::nearVec(g.direction.col(1), Vec3d::UnitY(), kDicomDecimalMm));
    EXPECT_TRUE(voxhap::test::nearVec(g.direction.col(2), Vec3d::UnitZ(), kDicomDecimalMm));
    // Independent of the transform code: GDCM's own origin of the most superior
    // file (instance 1) is where the volume puts its top slice.
    const Slice top = readDirectly(kCtDir / "1-001.dcm");
    EXPECT_TRUE(voxhap::test::nearVec(sVolume->indexToWorld(Vec3d(0, 0, 133)), top.origin, kDicomDecimalMm));
}

TEST_F(RealCt, VertebralBodyReadsAsBone)
{
    // Found by inspecting the data: the body of a lower thoracic vertebra, on
    // the posterior midline (x ~ 0) in front of the spinal canal, 296 mm up.
    const Vec3d vertebralBody(4.3, 120.5, 295.91);
    // Cancellous bone here reads 200-300 HU; muscle, fat, blood and organs
    // stay below ~150 HU away from contrast-filled vessels.
    constexpr float kBoneHu = 150.0f;
    const Vec3d ijk = sVolume->worldToIndex(vertebralBody);
    const openvdb::Coord c(int(std::lround(ijk.x())), int(std::lround(ijk.y())), int(std::lround(ijk.z())));
    auto acc = huGrid(*sVolume)->getConstAccessor();
    for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const openvdb::Coord n = c.offsetBy(dx, dy, dz);
                EXPECT_GT(acc.getValue(n), kBoneHu) << "voxel " << n;
            }
    // Just behind it (posterior, +y) lies the spinal canal: soft, not bone.
    EXPECT_LT(acc.getValue(c.offsetBy(0, 18, 0)), kBoneHu) << "spinal canal 19 mm behind";
}

TEST_F(RealCt, LiverLiesOnThePatientsRightThatIsMinusX)
{
    // In the upper abdomen (z 350-386 mm here) the liver fills the patient's
    // right: soft tissue (40-200 HU) right of the spine (-x in LPS) outnumbers
    // that on the left. Measured ratios are 1.5-2.3 per slice; 1.3 keeps margin
    // and would fail by far if left and right were swapped.
    constexpr double kMinRightToLeft = 1.3;
    const double spineX = 4.3; // the vertebral body above
    auto acc = huGrid(*sVolume)->getConstAccessor();
    std::int64_t right = 0, left = 0;
    for (int k = 88; k <= 100; k += 2) {
        for (int j = 0; j < 512; j += 2) {
            for (int i = 0; i < 512; i += 2) {
                const float hu = acc.getValue(openvdb::Coord(i, j, k));
                if (hu <= 40.0f || hu >= 200.0f) continue;
                (sVolume->indexToWorld(Vec3d(i, j, k)).x() < spineX ? right : left) += 1;
            }
        }
    }
    EXPECT_GT(double(right), kMinRightToLeft * double(left)) << right << " right vs " << left << " left";
}

TEST_F(RealCt, VoxelsAreTheRescaledStoredValuesExactly)
{
    const auto grid = huGrid(*sVolume);
    auto acc = grid->getConstAccessor();
    for (const char* name : {"1-001.dcm", "1-067.dcm"}) {
        const Slice s = readDirectly(kCtDir / name);
        const Vec3d ijk = sVolume->worldToIndex(s.origin);
        const int k = int(std::lround(ijk.z()));
        ASSERT_NEAR(ijk.z(), k, 1e-6) << name << " must fall on a slice";
        std::int64_t mismatches = 0;
        for (unsigned j = 0; j < s.rows; ++j) {
            for (unsigned i = 0; i < s.columns; ++i) {
                const double hu = s.hu[std::size_t(j) * s.columns + i];
                const openvdb::Coord c(int(i), int(j), k);
                const bool ok = hu < -950.0 ? !acc.isValueOn(c) : (acc.isValueOn(c) && acc.getValue(c) == float(hu));
                mismatches += ok ? 0 : 1;
            }
        }
        EXPECT_EQ(mismatches, 0) << name;
    }
}

TEST_F(RealCt, EveryVoxelOfEverySliceIsTheRescaledStoredValueInMinimalLeaves)
{
    // Every slice against GDCM's own decode (not the loader's reading of the
    // files): what a faster loader must keep bit for bit. Beyond the values,
    // the sparse layout: inactive voxels hold the background, and a leaf
    // exists exactly where an 8^3 block has an active voxel.
    const auto grid = huGrid(*sVolume);
    auto acc = grid->getConstAccessor();
    const voxhap::Vec3i dims = sVolume->indexBox().dims();
    std::set<openvdb::Coord> blocks; // origins of the 8^3 blocks that hold an active voxel
    std::int64_t active = 0, mismatches = 0, files = 0;
    for (const auto& entry : fs::directory_iterator(kCtDir)) {
        const Slice s = readDirectly(entry.path());
        ++files;
        const Vec3d ijk = sVolume->worldToIndex(s.origin);
        const int k = int(std::lround(ijk.z()));
        ASSERT_NEAR(ijk.z(), k, 1e-6) << entry.path();
        ASSERT_EQ(int(s.columns), dims.x());
        ASSERT_EQ(int(s.rows), dims.y());
        for (unsigned j = 0; j < s.rows; ++j) {
            for (unsigned i = 0; i < s.columns; ++i) {
                const double hu = s.hu[std::size_t(j) * s.columns + i];
                const openvdb::Coord c(int(i), int(j), k);
                const bool air = hu < -950.0;
                const float want = air ? kAirHu : float(hu);
                // Compared as bits: -0.0 and 0.0, or two NaNs, must not pass for each other.
                const float got = acc.getValue(c);
                const bool same = std::memcmp(&got, &want, sizeof got) == 0 && acc.isValueOn(c) == !air;
                mismatches += same ? 0 : 1;
                if (!air) {
                    ++active;
                    blocks.insert(openvdb::Coord(int(i) & ~7, int(j) & ~7, k & ~7));
                }
            }
        }
    }
    EXPECT_EQ(files, dims.z());
    EXPECT_EQ(mismatches, 0);
    EXPECT_EQ(std::int64_t(grid->activeVoxelCount()), active);
    EXPECT_EQ(grid->tree().leafCount(), blocks.size()) << "one leaf per block with an active voxel, no more";
    EXPECT_EQ(grid->tree().activeTileCount(), 0u) << "voxels stay voxels: no tolerance merges them into tiles";
    for (auto leaf = grid->tree().cbeginLeaf(); leaf; ++leaf) {
        ASSERT_TRUE(blocks.count(leaf->origin())) << leaf->origin();
        for (auto v = leaf->cbeginValueOff(); v; ++v) {
            ASSERT_EQ(*v, kAirHu) << v.getCoord() << ": an inactive voxel holds the background";
        }
    }
}

TEST_F(RealCt, HuRangeIsPlausibleAndAirIsSparse)
{
    const auto grid = huGrid(*sVolume);
    const auto range = openvdb::tools::minMax(grid->tree());
    const float lo = range.min(), hi = range.max();
    // Stored 12-bit unsigned (0..4095) with intercept -1000: -1000..3095 HU at most.
    EXPECT_GE(lo, -950.0f) << "active voxels are above the air threshold";
    EXPECT_LE(hi, 3095.0f);
    EXPECT_GT(hi, 1000.0f) << "cortical bone and contrast exceed 1000 HU";
    const double active = double(sReport->activeVoxels) / double(sReport->denseVoxels);
    EXPECT_GT(active, 0.2) << "the body fills a good part of the field of view";
    EXPECT_LT(active, 0.8) << "the air around the body is inactive";
    EXPECT_LT(double(sReport->memoryBytes), 0.6 * double(sReport->denseVoxels) * sizeof(float))
        << "issue 6 target: at most 0.6 x a dense float array once air is inactive";
}

} // namespace

TEST(DicomNative, EveryRealCtFileReadsAsGdcmDecodesIt)
{
    VOXHAP_REQUIRE_DIR(kCtDir);
    voxhap::test::expectNativeEqualsGdcm({kCtDir});
}
