// SPDX-License-Identifier: Apache-2.0
/// @file TestCliConvert.cpp
/// @brief `voxhap convert` and `voxhap info` on DICOM series and .nrrd files,
/// run as a user would: outputs, series listing, quiet stderr when not on a
/// terminal, and one-line failures that leave no output behind.

#include "common/CliRunner.h"
#include "common/DicomWriter.h"
#include "common/SharedData.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;

const fs::path kCtDir = voxhap::test::realCtDir();

using Result = voxhap::test::CliResult;

class CliConvert : public voxhap::test::CliTest {
protected:
    /// A small CT series of @p n slices in folder @p dir, series @p uid.
    void writeSeries(const fs::path& dir, int n, const std::string& uid, double step = 2.0) const
    {
        fs::create_directories(dir);
        for (int k = 0; k < n; ++k) {
            voxhap::test::SyntheticSlice s;
            s.seriesUid = uid;
            s.position.z() = k * step;
            s.pixels.assign(std::size_t(s.rows * s.columns), std::int16_t(1000 + k));
            voxhap::test::writeSyntheticSlice(s, dir / (uid.substr(uid.size() - 1) + "-" + std::to_string(k) + ".dcm"));
        }
    }
};

void expectFailure(const Result& r, int code, const std::string& fragment)
{
    voxhap::test::expectError(r, code, fragment);
}

TEST_F(CliConvert, RealCtToVdbAndNrrd)
{
    VOXHAP_REQUIRE_DIR(kCtDir);
    const Result vdb = run("convert '" + kCtDir.string() + "' ct.vdb --json");
    ASSERT_EQ(vdb.exitCode, 0) << vdb.err;
    EXPECT_TRUE(vdb.err.empty()) << "no progress bar when stderr is not a terminal: " << vdb.err;
    const auto j = nlohmann::json::parse(vdb.out);
    EXPECT_EQ(j["dims"], nlohmann::json({512, 512, 134}));
    const double active = j["active_fraction"].get<double>();
    EXPECT_GT(active, 0.0);
    EXPECT_LT(active, 1.0);
    const Result info = run("info ct.vdb --json");
    ASSERT_EQ(info.exitCode, 0) << info.err;
    EXPECT_NE(info.out.find("\"hu\""), std::string::npos);

    const Result nrrd = run("convert '" + kCtDir.string() + "' ct.nrrd");
    ASSERT_EQ(nrrd.exitCode, 0) << nrrd.err;
    EXPECT_NE(nrrd.out.find("wrote  ct.nrrd"), std::string::npos) << nrrd.out;
    std::ifstream in(mDir / "ct.nrrd", std::ios::binary);
    std::string magic(8, '\0');
    in.read(magic.data(), 8);
    EXPECT_EQ(magic, "NRRD0004");
    const Result back = run("info ct.nrrd --json");
    ASSERT_EQ(back.exitCode, 0) << back.err;
    const auto b = nlohmann::json::parse(back.out);
    EXPECT_EQ(b["dimensions"], nlohmann::json({512, 512, 134}));
    EXPECT_EQ(b["active_voxels"], j["active_voxels"]) << "the .nrrd round trip keeps exactly the active voxels";
    EXPECT_EQ(b["modality"], "CT");
}

TEST_F(CliConvert, InfoListsTheSeriesAndConvertChoosesOne)
{
    writeSeries(mDir / "in", 5, "1.2.826.0.1.3680043.2.1125.99.7");
    writeSeries(mDir / "in", 3, "1.2.826.0.1.3680043.2.1125.99.8", 4.0);
    const Result info = run("info in");
    ASSERT_EQ(info.exitCode, 0) << info.err;
    EXPECT_NE(info.out.find("1.2.826.0.1.3680043.2.1125.99.7"), std::string::npos) << info.out;
    EXPECT_NE(info.out.find("1.2.826.0.1.3680043.2.1125.99.8"), std::string::npos) << info.out;
    const Result second = run("convert in second.vdb --series 2 --json");
    ASSERT_EQ(second.exitCode, 0) << second.err;
    EXPECT_EQ(nlohmann::json::parse(second.out)["dims"], nlohmann::json({16, 12, 3}));
    EXPECT_EQ(nlohmann::json::parse(second.out)["series_count"], 2);
}

TEST_F(CliConvert, BadInputsFailWithOneLineAndNoOutput)
{
    writeSeries(mDir / "gap", 4, "1.2.826.0.1.3680043.2.1125.99.9");
    fs::remove(mDir / "gap" / "9-2.dcm");
    expectFailure(run("convert gap out.vdb"), 1, "missing");
    EXPECT_FALSE(fs::exists(mDir / "out.vdb"));
    const Result resampled = run("convert gap out.vdb --resample --json");
    ASSERT_EQ(resampled.exitCode, 0) << resampled.err;
    EXPECT_EQ(nlohmann::json::parse(resampled.out)["dims"], nlohmann::json({16, 12, 4}));
    EXPECT_TRUE(nlohmann::json::parse(resampled.out)["resampled"].get<bool>());

    writeSeries(mDir / "cut", 3, "1.2.826.0.1.3680043.2.1125.99.6");
    fs::resize_file(mDir / "cut" / "6-1.dcm", 700);
    expectFailure(run("convert cut out.nrrd"), 1, "6-1.dcm");
    EXPECT_FALSE(fs::exists(mDir / "out.nrrd"));

    std::ofstream(mDir / "huge.nrrd") << "NRRD0004\ntype: float\ndimension: 3\nspace: LPS\nsizes: 4000 4000 4000\n"
                                         "space directions: (1,0,0) (0,1,0) (0,0,1)\nendian: little\nencoding: raw\n\n";
    expectFailure(run("convert huge.nrrd out.vdb --memory-cap 1024"), 1, "memory cap");
    expectFailure(run("convert missing-dir out.vdb"), 1, "missing-dir");
    expectFailure(run("convert gap out.png"), 2, "out.png");
    std::ofstream(mDir / "notes.txt") << "hello\n";
    expectFailure(run("convert notes.txt out.vdb"), 1, "unknown format");
    expectFailure(run("info gap --series 7"), 1, "series '7'");
    for (const auto& e : fs::directory_iterator(mDir)) {
        EXPECT_EQ(e.path().string().find(".tmp."), std::string::npos) << "temporary file left: " << e.path();
    }
}

TEST_F(CliConvert, RealMrAsAUserBringsIt)
{
    // The two-echo field map: the table is shown, the load refused in one
    // line naming --volume; one echo loads with --volume and --resample, as
    // an intensity grid called a field map.
    VOXHAP_REQUIRE_DIR(voxhap::test::fieldMapDir());
    const std::string fieldMap = "'" + voxhap::test::fieldMapDir().string() + "'";
    const Result refused = run("info " + fieldMap);
    expectFailure(refused, 1, "--volume 1..2");
    EXPECT_NE(refused.out.find("field map"), std::string::npos) << refused.out;
    EXPECT_NE(refused.out.find("volumes by echo"), std::string::npos) << refused.out;
    const Result echo = run("convert " + fieldMap + " echo1.vdb --volume 1 --resample --json");
    ASSERT_EQ(echo.exitCode, 0) << echo.err;
    const auto j = nlohmann::json::parse(echo.out);
    EXPECT_EQ(j["mr_weighting"], "field map");
    EXPECT_EQ(j["volume"], 1);
    EXPECT_TRUE(j["resampled"].get<bool>());
    EXPECT_EQ(j["source_voxels_outside_grid"], 0);

    // The diffusion mosaics: one volume of 128 × 128 × 25.
    VOXHAP_REQUIRE_DIR(voxhap::test::dwiMosaicDir());
    const Result b0 = run("convert '" + voxhap::test::dwiMosaicDir().string() + "' b0.vdb --volume 1 --json");
    ASSERT_EQ(b0.exitCode, 0) << b0.err;
    EXPECT_EQ(nlohmann::json::parse(b0.out)["dims"], nlohmann::json({128, 128, 25}));
    EXPECT_EQ(nlohmann::json::parse(b0.out)["mr_weighting"], "diffusion");

    // The MPRAGE: T1-weighted, normalised; the text file beside it set aside.
    VOXHAP_REQUIRE_DIR(voxhap::test::mprageDir());
    const Result info = run("info '" + voxhap::test::mprageDir().string() + "' --json");
    ASSERT_EQ(info.exitCode, 0) << info.err;
    const auto m = nlohmann::json::parse(info.out);
    EXPECT_EQ(m["mr_weighting"], "T1-weighted");
    EXPECT_EQ(m["dicom_skipped"]["counts"]["not DICOM"], 1);
    EXPECT_EQ(m["units"]["t1"], "ms");
}

TEST_F(CliConvert, SkipBadAndDeclarationsFromTheCommandLine)
{
    writeSeries(mDir / "cut", 4, "1.2.826.0.1.3680043.2.1125.99.5");
    fs::resize_file(mDir / "cut" / "5-3.dcm", 700);
    expectFailure(run("convert cut out.vdb"), 1, "--skip-bad");
    EXPECT_FALSE(fs::exists(mDir / "out.vdb"));
    const Result kept = run("convert cut out.vdb --skip-bad --json");
    ASSERT_EQ(kept.exitCode, 0) << kept.err;
    EXPECT_EQ(nlohmann::json::parse(kept.out)["dims"], nlohmann::json({16, 12, 3}));
    EXPECT_EQ(nlohmann::json::parse(kept.out)["skipped_bad_files"], 1);
    const Result listed = run("info cut --skip-bad");
    ASSERT_EQ(listed.exitCode, 0) << listed.err;
    EXPECT_NE(listed.out.find("5-3.dcm"), std::string::npos) << listed.out;

    // --channel takes auto, hu, mr (and t1, read as mr); anything else is a usage error.
    expectFailure(run("info cut --channel ct"), 2, "--channel");
}

} // namespace
