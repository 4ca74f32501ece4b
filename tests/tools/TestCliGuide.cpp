// SPDX-License-Identifier: Apache-2.0
/// @file TestCliGuide.cpp
/// @brief `--guide FILE --guide-path N` of `voxhap simulate` and `voxhap serve` as a
/// user runs them: the planned line from `voxhap plan`'s report or markups, the
/// guidance's pull in the summary against its closed form, one-line errors.

#include "common/CliRunner.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <Eigen/Core>
#include <filesystem>
#include <fstream>

namespace {

namespace fs = std::filesystem;
using Result = voxhap::test::CliResult;
using voxhap::test::expectFailure;
using voxhap::test::expectUsageError;

/// The summary prints doubles at full precision: only the closed form's own round-off.
constexpr double kClosedFormN = 1e-9;

class CliGuide : public voxhap::test::CliTest {
protected:
    nlohmann::json json(const Result& r) const { return nlohmann::json::parse(r.out); }
    void write(const fs::path& p, const std::string& text) const { std::ofstream(mDir / p) << text; }
};

TEST_F(CliGuide, SimulateIsPulledTowardThePlannedLineByItsClosedForm)
{
    // The kyung path on the torso phantom, planned (analysed) by `voxhap plan`.
    ASSERT_EQ(run("phantom torso --spacing 1.5 -o torso.vdb").exitCode, 0);
    const Result plan = run("plan torso.vdb --entry 40,-3.6,0 --target 5,-78,0 --out plan --no-views");
    ASSERT_EQ(plan.exitCode, 0) << plan.err;
    ASSERT_TRUE(fs::exists(mDir / "plan/report.json"));

    // On the planned line: no pull at all.
    const Result on = run("simulate torso.vdb --scene kyung --entry 40,-3.6,0 --target 5,-78,0 --depth 30 "
                          "--guide plan/report.json --guide-path 1 --no-plot --json -o on");
    ASSERT_EQ(on.exitCode, 0) << on.err;
    const auto g = json(on)["guidance"];
    EXPECT_LE(g["peak_force_N"].get<double>(), 1e-12);
    EXPECT_LE(g["max_offset_mm"].get<double>(), 1e-12);

    // The insertion 1 mm beside it along x: the pull is k·r, r the distance from the
    // planned line, k = 0.2 N/mm (the default; kyung names no guidance block).
    const Eigen::Vector3d e(40, -3.6, 0), t(5, -78, 0), w = (t - e).normalized(), dx(1, 0, 0);
    const double r = (dx - dx.dot(w) * w).norm();
    const Result beside = run("simulate torso.vdb --scene kyung --entry 41,-3.6,0 --target 6,-78,0 --depth 30 "
                              "--guide plan/paths.mrk.json --no-plot --json -o beside");
    ASSERT_EQ(beside.exitCode, 0) << beside.err;
    EXPECT_NEAR(json(beside)["guidance"]["max_offset_mm"].get<double>(), r, 1e-9);
    EXPECT_NEAR(json(beside)["guidance"]["peak_force_N"].get<double>(), 0.2 * r, kClosedFormN);

    // The human summary says where the guide came from and what it did.
    const Result text = run("simulate torso.vdb --scene kyung --entry 41,-3.6,0 --target 6,-78,0 --depth 30 "
                            "--guide plan/report.json --no-plot -o text");
    ASSERT_EQ(text.exitCode, 0) << text.err;
    EXPECT_NE(text.out.find("guidance toward path 1 of plan/report.json"), std::string::npos) << text.out;
    EXPECT_NE(text.out.find("guidance"), std::string::npos);

    // Without --guide the summary has no guidance (off by default).
    const Result plain =
        run("simulate torso.vdb --scene kyung --entry 41,-3.6,0 --target 6,-78,0 --depth 30 --no-plot --json -o p");
    ASSERT_EQ(plain.exitCode, 0) << plain.err;
    EXPECT_FALSE(json(plain).contains("guidance"));

    // serve takes the same options and reports the line in its metrics.
    const Result serve = run("serve --scene kyung --device sim --duration 0.5 --guide plan/report.json --json -o s");
    ASSERT_EQ(serve.exitCode, 0) << serve.err;
    const auto sg = json(serve)["guidance"];
    EXPECT_EQ(sg["path"], 1);
    EXPECT_NEAR(sg["entry"][0].get<double>(), 40.0, 1e-9);
    EXPECT_NEAR(sg["target"][1].get<double>(), -78.0, 1e-9);
}

TEST_F(CliGuide, BadGuidesFailInOneLineNamingTheFileAndField)
{
    write(
        "report.json", R"({"schema": "voxhap-plan-report/1", "paths": [{"entry": [0, 0, 0], "target": [0, -40, 0]}]})");
    expectFailure(run("simulate --scene senac-average --guide report.json --guide-path 3 --no-plot -o x"),
        "report.json: paths: no path 3 (the file has 1)");
    write(
        "bad.json", R"({"schema": "voxhap-plan-report/1", "paths": [{"entry": [0, "a", 0], "target": [0, -40, 0]}]})");
    expectFailure(
        run("simulate --scene senac-average --guide bad.json --no-plot -o x"), "bad.json: paths[0].entry: must be");
    write("other.json", R"({"hello": 1})");
    expectFailure(run("simulate --scene senac-average --guide other.json --no-plot -o x"),
        "other.json: schema: must be \"voxhap-plan/1\" or \"voxhap-plan-report/1\"");
    expectFailure(run("simulate --scene senac-average --guide missing.json --no-plot -o x"), "missing.json");
    expectUsageError(run("simulate --scene senac-average --guide-path 2 --no-plot -o x"), "--guide-path needs --guide");
    expectUsageError(run("serve --scene senac-average --guide-path 2 -o x"), "--guide-path needs --guide");
    EXPECT_FALSE(fs::exists(mDir / "x"));
}

} // namespace
