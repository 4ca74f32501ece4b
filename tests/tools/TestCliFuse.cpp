// SPDX-License-Identifier: Apache-2.0
/// @file TestCliFuse.cpp
/// @brief `voxhap fuse` as a user runs it: a phantom's CT and its moved MR
/// fused, the record against the true move, `info` and `render --fusion` on
/// the result; and each refusal in one line with exit 1 and no output left,
/// beside the input that gets past it.

#include "common/CliRunner.h"
#include "common/DicomWriter.h"
#include "common/SharedData.h"

#include "phantoms/PhantomScans.h"
#include "volume/Grids.h"
#include "volume/VolumeFile.h"
#include "volume/io/NrrdFile.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

namespace {

namespace fs = std::filesystem;
using voxhap::Mat3d;
using voxhap::Vec3d;
using Result = voxhap::test::CliResult;

/// The MR's move: 8° about S–I and a shift on every axis [mm].
constexpr double kTurnDeg = 8.0;
const Vec3d kShift(6.0, -4.0, 10.0);
/// The phantoms' registration error is about 0.3 mm mean (docs/reference.md
/// "CT and MR fusion"); the fuse command must give the library's answer, so
/// the tolerance is the target for the phantoms, 1 mm.
constexpr double kPhantomTreMm = 1.0;

class CliFuse : public voxhap::test::CliTest {
protected:
    void SetUp() override
    {
        CliTest::SetUp();
        namespace v = voxhap::volume;
        const auto& table = v::TissueTable::builtin();
        v::PhantomSpec spec;
        spec.kind = "lumbar";
        const v::PhantomModel model = v::phantomModel(spec, table);
        v::GridSpec grid;
        grid.spacing = Vec3d(1.5, 1.5, 1.5);
        v::saveNrrd(v::phantomCtScan(model, grid, table), v::Channel::Hu, mDir / "ct.nrrd", v::NrrdEncoding::Raw);
        v::PhantomMrScan scan;
        scan.rotation = Eigen::AngleAxisd(kTurnDeg * 3.14159265358979323846 / 180.0, Vec3d::UnitZ()).toRotationMatrix();
        scan.translationMm = kShift;
        const v::Volume mr = v::phantomMrScan(model, table, scan, &mTruth);
        v::writePhantomMrScan(mr, scan.field, mDir / "mr.nrrd");
    }

    /// Neither output of a refused fuse exists.
    void expectNoOutput(const std::string& name) const
    {
        EXPECT_FALSE(fs::exists(mDir / (name + ".vdb"))) << name;
        EXPECT_FALSE(fs::exists(mDir / (name + ".tfm"))) << name;
    }

    /// A tiny DICOM series of patient @p id, modality @p modality, in @p dir.
    void writeDicom(const fs::path& dir, const std::string& modality, const std::string& id, int slices) const
    {
        fs::create_directories(dir);
        for (int k = 0; k < slices; ++k) {
            voxhap::test::SyntheticSlice s;
            s.modality = modality;
            s.seriesUid = modality == "CT" ? "1.2.826.0.1.3680043.2.1125.7.1" : "1.2.826.0.1.3680043.2.1125.7.2";
            s.patientId = id;
            s.patientName = "DOE^" + id;
            s.position.z() = 2.0 * k;
            if (modality == "MR") s.intercept = 0.0; // MR images carry no HU rescale
            s.pixels.assign(std::size_t(s.rows * s.columns), std::int16_t(modality == "CT" ? 1040 : 400 + k));
            voxhap::test::writeSyntheticSlice(s, dir / (std::to_string(k) + ".dcm"));
        }
    }

    voxhap::volume::PhantomScanTruth mTruth;
};

TEST_F(CliFuse, FusesAMovedPhantomMrAndInfoAndRenderShowTheRegistration)
{
    const Result r = run("fuse ct.nrrd mr.nrrd --out fused.vdb --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_TRUE(j.contains("mr_from_ct")) << r.out;
    Eigen::Matrix4d m;
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) m(a, b) = j["mr_from_ct"][a][b].get<double>();
    // Points through the phantom's block, against the true move.
    double sum = 0;
    int n = 0;
    for (double x : {-30.0, 0.0, 30.0})
        for (double y : {-40.0, -20.0, 0.0})
            for (double z : {-30.0, 0.0, 30.0}) {
                const Vec3d p(x, y, z);
                const Vec3d got = m.topLeftCorner<3, 3>() * p + m.topRightCorner<3, 1>();
                sum += (got - mTruth.apply(p)).norm();
                ++n;
            }
    EXPECT_LE(sum / n, kPhantomTreMm);
    EXPECT_TRUE(fs::exists(mDir / "fused.tfm"));
    EXPECT_GT(j["damping_from_t1_fraction"].get<double>(), 0.0) << "a T1 map gives fat and muscle their damping";
    EXPECT_EQ(j["channel_sources"]["t1"].get<std::string>().find("mr.nrrd") != std::string::npos, true) << r.out;

    const Result info = run("info fused.vdb");
    ASSERT_EQ(info.exitCode, 0) << info.err;
    EXPECT_NE(info.out.find("registration"), std::string::npos) << info.out;
    EXPECT_NE(info.out.find("mr.nrrd"), std::string::npos) << info.out;

    // The fused volume is a .vdb like any other: segment and render read it.
    const Result seg = run("segment fused.vdb --out segmented.vdb");
    EXPECT_EQ(seg.exitCode, 0) << seg.err;
    EXPECT_TRUE(fs::exists(mDir / "segmented.vdb"));
    const Result plain = run("render fused.vdb --out plain");
    EXPECT_EQ(plain.exitCode, 0) << plain.err;

    const Result views = run("render fused.vdb --fusion --out views");
    ASSERT_EQ(views.exitCode, 0) << views.err;
    for (const char* plane : {"axial", "coronal", "sagittal"}) {
        const fs::path png = mDir / "views" / (std::string("fusion-") + plane + ".png");
        ASSERT_TRUE(fs::exists(png)) << png;
        EXPECT_GT(fs::file_size(png), 4000u) << png << ": a sheet of six panels, not an empty image";
    }
}

TEST_F(CliFuse, TheMrGivenFirstIsRefusedAndTheRightOrderIsNot)
{
    voxhap::test::expectFailure(run("fuse mr.nrrd ct.nrrd --out swapped.vdb"), "give the CT first");
    expectNoOutput("swapped");
    voxhap::test::expectFailure(run("fuse ct.nrrd ct.nrrd --out twice.vdb"), "given as the MR, but it is a CT");
    expectNoOutput("twice");
}

TEST_F(CliFuse, AnMrOfOneSliceIsRefused)
{
    namespace v = voxhap::volume;
    const v::Volume mr = v::loadVolume(mDir / "mr.nrrd");
    const auto box = mr.indexBox();
    v::IndexBox one = box;
    one.max.z() = one.min.z() + (box.max.z() - box.min.z()) / 2;
    one.min.z() = one.max.z();
    v::Volume slice(mr.geometry(), one);
    slice.setGrid(v::Channel::T1, std::const_pointer_cast<openvdb::GridBase>(mr.grid(v::Channel::T1))->deepCopyGrid());
    slice.metadata() = mr.metadata();
    v::saveNrrd(slice, v::Channel::T1, mDir / "slice.nrrd", v::NrrdEncoding::Raw);
    voxhap::test::expectFailure(run("fuse ct.nrrd slice.nrrd --out one.vdb"), "slice.nrrd");
    expectNoOutput("one");
}

TEST_F(CliFuse, SeriesOfDifferentPatientsAreRefusedUnlessTheUserSaysSo)
{
    writeDicom(mDir / "ct-dicom", "CT", "PIG1", 8);
    writeDicom(mDir / "mr-dicom", "MR", "PIG2", 8);
    const Result refused = run("fuse ct-dicom mr-dicom --out other.vdb");
    voxhap::test::expectFailure(refused, "patient");
    expectNoOutput("other");
    // Control: the same series with --different-patients pass the patient check
    // (whatever the registration of two tiny blocks then says).
    const Result past = run("fuse ct-dicom mr-dicom --out other.vdb --different-patients");
    EXPECT_EQ(past.err.find("patient"), std::string::npos) << past.err;
}

TEST_F(CliFuse, AFourDimensionalMrNeedsItsVolume)
{
    const fs::path dwi = voxhap::test::sharedDataDir() / "mr-dwi-prisma" / "dwi-mosaic";
    VOXHAP_REQUIRE_DIR(dwi);
    voxhap::test::expectFailure(run("fuse ct.nrrd '" + dwi.string() + "' --out dwi.vdb"), "--volume");
    expectNoOutput("dwi");
    // Control: the option the refusal names gets the load past it (the phantom
    // and the volunteer's head then fail later, on the registration's checks).
    const Result chosen = run("fuse ct.nrrd '" + dwi.string() + "' --out dwi.vdb --volume 2");
    EXPECT_EQ(chosen.err.find("--volume"), std::string::npos) << chosen.err;
}

TEST_F(CliFuse, TheOutputMustBeAVdb)
{
    voxhap::test::expectUsageError(run("fuse ct.nrrd mr.nrrd --out fused.nrrd"), ".vdb");
    expectNoOutput("fused");
}

} // namespace
