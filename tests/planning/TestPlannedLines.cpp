// SPDX-License-Identifier: Apache-2.0
/// @file TestPlannedLines.cpp
/// @brief planning::parseReportPaths and loadPlannedLines: the planned lines
/// guidance reads (issue 23 item 2), from a report `voxhap plan` wrote or from
/// Slicer markups, and refusals naming the file and the field.

#include "common/TempDirTest.h"

#include "core/Errors.h"
#include "planning/Report.h"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

namespace voxhap::planning {
namespace {

/// Numbers written by nlohmann::json and read back: exact (shortest round trip).
constexpr double kExact = 0.0;

std::string refusal(const std::string& json)
{
    try {
        (void)parseReportPaths(json, "r.json");
    } catch (const ValueError& e) {
        return e.what();
    }
    return "";
}

TEST(PlannedLines, ReportPathsInRankOrder)
{
    const auto lines = parseReportPaths(
        R"({"schema": "voxhap-plan-report/1", "paths": [{"rank": 1, "entry": [40, -3.6, 0], "target": [5, -78, 0]},
            {"rank": 2, "entry": [1, 2, 3], "target": [4, 5, 6.5]}]})",
        "r.json");
    ASSERT_EQ(lines.size(), 2u);
    EXPECT_EQ(lines[0].name, "path 1");
    EXPECT_NEAR((lines[0].entry - Vec3d(40, -3.6, 0)).norm(), 0.0, kExact);
    EXPECT_NEAR((lines[1].target - Vec3d(4, 5, 6.5)).norm(), 0.0, kExact);
    EXPECT_TRUE(parseReportPaths(R"({"schema": "voxhap-plan-report/1", "paths": []})", "r.json").empty());
}

TEST(PlannedLines, RefusalsNameTheField)
{
    EXPECT_NE(refusal(R"({"schema": "other", "paths": []})").find("r.json: schema: must be"), std::string::npos);
    EXPECT_NE(
        refusal(R"({"schema": "voxhap-plan-report/1"})").find("r.json: paths: must be an array"), std::string::npos);
    EXPECT_NE(refusal(R"({"schema": "voxhap-plan-report/1", "paths": [{"entry": [0, 0], "target": [1, 1, 1]}]})")
                  .find("r.json: paths[0].entry: must be [x, y, z] in mm"),
        std::string::npos);
    EXPECT_NE(refusal(R"({"schema": "voxhap-plan-report/1", "paths": [{"entry": [0, 0, 0], "target": [0, 0, 0]}]})")
                  .find("r.json: paths[0]: entry and target coincide"),
        std::string::npos);
    EXPECT_NE(refusal("{not json").find("r.json"), std::string::npos);
}

class PlannedFiles : public test::TempDirTest { };

TEST_F(PlannedFiles, ReportsAndMarkupsAreToldApartByContent)
{
    const MarkupLine line{"a", Vec3d(1, 2, 3), Vec3d(4, 5, 6)};
    writeMarkups({line}, mDir / "paths.mrk.json");
    const auto fromMarkups = loadPlannedLines(mDir / "paths.mrk.json");
    ASSERT_EQ(fromMarkups.size(), 1u);
    EXPECT_NEAR((fromMarkups[0].target - line.target).norm(), 0.0, 1e-12); // markups store %.17g-exact numbers
    std::ofstream(mDir / "report.json")
        << R"({"schema": "voxhap-plan-report/1", "paths": [{"entry": [1, 2, 3], "target": [4, 5, 6]}]})";
    ASSERT_EQ(loadPlannedLines(mDir / "report.json").size(), 1u);
    std::ofstream(mDir / "other.json") << R"({"x": 1})";
    EXPECT_THROW(loadPlannedLines(mDir / "other.json"), ValueError);
    EXPECT_THROW(loadPlannedLines(mDir / "missing.json"), IoError);
}

} // namespace
} // namespace voxhap::planning
