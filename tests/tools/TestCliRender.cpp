// SPDX-License-Identifier: Apache-2.0
/// @file TestCliRender.cpp
/// @brief `voxhap render` as a user runs it: the four views and the contact
/// sheet at the sizes the bounds give, the display path said on stderr, slices
/// without any display or Xvfb, and one-line refusals.

#include "common/CliRunner.h"
#include "common/SharedData.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <filesystem>
#include <fstream>

namespace {

namespace fs = std::filesystem;

using Result = voxhap::test::CliResult;

/// Width and height from a PNG's IHDR chunk (bytes 16..23, big-endian).
std::array<int, 2> pngSize(const fs::path& file)
{
    std::ifstream in(file, std::ios::binary);
    unsigned char h[24] = {};
    in.read(reinterpret_cast<char*>(h), 24);
    if (!in || h[1] != 'P' || h[2] != 'N' || h[3] != 'G') return {0, 0};
    const auto be = [&](int o) { return (h[o] << 24) | (h[o + 1] << 16) | (h[o + 2] << 8) | h[o + 3]; };
    return {be(16), be(20)};
}

class CliRender : public voxhap::test::CliTest {
protected:
    void SetUp() override
    {
        CliTest::SetUp();
        // Bone sphere r 10 mm centred at (0, −20, 0) in 40 mm of fat; x, z in
        // −25..25, y in −40..5 (5 mm of air above the skin); 1 mm voxels.
        const Result r = run("phantom sphere --sphere-tissue cortical_bone --spacing 1 -o s.vdb");
        ASSERT_EQ(r.exitCode, 0) << r.err;
        std::ofstream(mDir / "plan.json")
            << R"({"schema": "voxhap-plan/1", "paths": [{"entry": [0, 0, 0], "target": [0, -20, 0]}]})";
    }
};

TEST_F(CliRender, FourViewsAndContactSheet)
{
    const Result r = run("render s.vdb --views axial,sagittal,coronal,3d --mode mip --path plan.json --point 0,-20,0 "
                         "--out out --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    // Which path the views took: one line, naming the display or the Xvfb started.
    EXPECT_EQ(r.errLines(), 1u) << r.err;
    EXPECT_NE(r.err.find("slices without GL"), std::string::npos) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["views"].size(), 4u);
    // 1 mm pixels over the 50 × 45 × 50 mm box (x, y, z).
    const std::pair<const char*, std::array<int, 2>> expected[] = {{"axial.png", {50, 45}}, {"sagittal.png", {45, 50}},
        {"coronal.png", {50, 50}}, {"3d-mip.png", {50, 50}}, {"sheet.png", {50 + 4 + 50, 50 + 4 + 50}}};
    for (const auto& [name, size] : expected) EXPECT_EQ(pngSize(mDir / "out" / name), size) << name;
    for (const auto& e : fs::directory_iterator(mDir / "out")) {
        EXPECT_EQ(e.path().extension(), ".png") << "no temporary left: " << e.path();
    }
}

TEST_F(CliRender, SlicesWithoutDisplayOrXvfb)
{
    // No $DISPLAY and no Xvfb on the PATH: the slices still come, the 3D view
    // fails with one line, and the process is not aborted by VTK.
    const Result r = run("render s.vdb --out out", "env -u DISPLAY PATH=/nonexistent");
    voxhap::test::expectFailure(r, "Xvfb not installed");
    for (const char* name : {"axial.png", "sagittal.png", "coronal.png", "sheet.png"}) {
        EXPECT_TRUE(fs::exists(mDir / "out" / name)) << name;
    }
    EXPECT_FALSE(fs::exists(mDir / "out" / "3d-colour.png"));
    // Slices alone need no display at all, and say nothing about one.
    const Result slices = run("render s.vdb --views axial --out only", "env -u DISPLAY PATH=/nonexistent");
    EXPECT_EQ(slices.exitCode, 0) << slices.err;
    EXPECT_TRUE(slices.err.empty()) << slices.err;
}

TEST_F(CliRender, RefusesWithOneLine)
{
    voxhap::test::expectUsageError(run("render s.vdb --views axial,oblique"), "unknown view 'oblique'");
    voxhap::test::expectUsageError(run("render s.vdb --mode xray"), "unknown mode 'xray'");
    voxhap::test::expectUsageError(run("render s.vdb --window 0,40"), "window");
    // A CT preset on MR is refused: HU windows show nothing true there.
    if (std::filesystem::is_directory(voxhap::test::flash2dDir()) || voxhap::test::sharedDataRequired()) {
        voxhap::test::expectUsageError(
            run("render '" + voxhap::test::flash2dDir().string() + "' --views axial --window bone"), "this is MR");
    }
    voxhap::test::expectUsageError(run("render s.vdb --views axial --point 999,0,0"), "--point");
    std::ofstream(mDir / "bad.json") << R"({"schema": "voxhap-plan/1", "paths": [{"entry": [0, 0, 0]}]})";
    voxhap::test::expectFailure(run("render s.vdb --path bad.json --out bad"), "bad.json: paths[0].target");
    EXPECT_FALSE(fs::exists(mDir / "bad")) << "refused before anything is written";
    voxhap::test::expectFailure(run("render missing.vdb --views axial"), "missing.vdb");
}

} // namespace

namespace {

using CliPlot = voxhap::test::CliTest;

TEST_F(CliPlot, ForceDepthFromSimulateAndFromASession)
{
    const Result sim = run("simulate --scene senac-average --no-plot -o sim");
    ASSERT_EQ(sim.exitCode, 0) << sim.err;
    const Result a = run("plot sim --json");
    ASSERT_EQ(a.exitCode, 0) << a.err;
    const auto j = nlohmann::json::parse(a.out);
    EXPECT_GT(j["layers"].get<int>(), 3);
    EXPECT_GT(j["events"].get<int>(), 0);
    EXPECT_EQ(pngSize(mDir / "sim" / "force-depth.png"), (std::array<int, 2>{1200, 700}));
    // A served session: session.csv and events.csv as `voxhap serve` writes them.
    fs::create_directories(mDir / "srv");
    std::ofstream(mDir / "srv" / "session.csv")
        << "t_s,tip_x_mm,tip_y_mm,tip_z_mm,dir_x,dir_y,dir_z,fx_N,fy_N,fz_N,plunger_N,depth_mm,axial_N,layer,state,"
           "fault,"
           "critical,plunger_fraction\n0,0,1,0,0,-1,0,0,0,0,0,-1,0,,outside,0,0,nan\n"
           "0.1,0,-2,0,0,-1,0,0,1,0,0,2,1,skin,punctured,0,0,nan\n";
    std::ofstream(mDir / "srv" / "events.csv") << "t_s,depth_mm,event,layer\n0.1,2,pop,skin\n";
    const Result b = run("plot srv/session.csv -o s.png");
    ASSERT_EQ(b.exitCode, 0) << b.err;
    EXPECT_EQ(pngSize(mDir / "s.png"), (std::array<int, 2>{1200, 700}));
    std::ofstream(mDir / "bad.csv") << "t_s,depth_mm\n";
    voxhap::test::expectFailure(run("plot bad.csv"), "bad.csv: line 1");
}

} // namespace
