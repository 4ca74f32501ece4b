// SPDX-License-Identifier: Apache-2.0
/// @file TestPlanFile.cpp
/// @brief Plan files (planning/PlanFile.h): plan.json, a planning report's
/// paths and Slicer line markups, told apart by content; what is read, and
/// one-line errors naming the file and the field for what is refused.

#include "common/TempDirTest.h"
#include "common/Tolerances.h"

#include "core/Errors.h"
#include "planning/Markups.h"
#include "planning/PlanFile.h"

#include <fstream>

namespace voxhap::planning {
namespace {

using test::nearVec;

class PlanFiles : public test::TempDirTest {
protected:
    std::filesystem::path write(const std::string& name, const std::string& text) const
    {
        const auto p = mDir / name;
        std::ofstream(p) << text;
        return p;
    }
};

TEST_F(PlanFiles, ReadsPathsAndNeedle)
{
    const Plan plan = loadPlan(write("plan.json", R"({"schema": "voxhap-plan/1", "paths": [
        {"name": "L3", "entry": [10, -5, 3], "target": [0, -60, 3],
         "needle": {"tip": [8, -20, 3], "direction": [0, -2, 0], "length_mm": 120}},
        {"entry": [1, 2, 3], "target": [4, 5, 6]}]})"));
    ASSERT_EQ(plan.paths.size(), 2u);
    EXPECT_EQ(plan.paths[0].name, "L3");
    EXPECT_TRUE(nearVec(plan.paths[0].entry, Vec3d(10, -5, 3), 0.0));
    ASSERT_TRUE(plan.paths[0].needle);
    EXPECT_TRUE(nearVec(plan.paths[0].needle->direction, Vec3d(0, -1, 0), 1e-15)); // normalised
    EXPECT_TRUE(nearVec(plan.paths[0].needle->hub(), Vec3d(8, 100, 3), 1e-12));
    EXPECT_EQ(plan.paths[1].name, "path 2");
    EXPECT_FALSE(plan.paths[1].needle);
}

TEST_F(PlanFiles, RefusesWithFileAndField)
{
    const auto refused = [&](const std::string& text, const std::string& field) {
        test::expectRefused<ValueError>([](const auto& p) { loadPlan(p); }, write("bad.json", text), field);
    };
    refused(R"({"schema": "voxhap-plan/2", "paths": []})", "schema: must be \"voxhap-plan/1\" or");
    refused(R"({"x": 1})", "schema: must be");
    refused(R"({"schema": "voxhap-plan/1"})", "paths");
    refused(R"({"schema": "voxhap-plan/1", "paths": []})", "paths");
    refused(R"({"schema": "voxhap-plan/1", "paths": [{"entry": [1, 2], "target": [0, 0, 0]}]})", "paths[0].entry");
    refused(R"({"schema": "voxhap-plan/1", "paths": [{"entry": [1, 2, 3]}]})", "paths[0].target");
    refused(R"({"schema": "voxhap-plan/1", "paths": [{"entry": [1, 2, 3], "target": [1, 2, 3]}]})", "paths[0].target");
    refused(R"({"schema": "voxhap-plan/1", "paths": [{"entry": [1, 2, 3], "target": [0, 0, 0], "colour": 1}]})",
        "paths[0].colour");
    refused(R"({"schema": "voxhap-plan/1", "paths": [{"entry": [1, 2, 3], "target": [0, 0, 0],
              "needle": {"tip": [0, 0, 0], "direction": [0, 0, 0]}}]})",
        "paths[0].needle.direction");
    refused(R"({"schema": "voxhap-plan/1", "paths": [)", "not valid JSON");
    test::expectRefused<IoError>([](const auto& p) { loadPlan(p); }, mDir / "absent.json", "cannot open");
}

TEST_F(PlanFiles, SlicerLineMarkupsInRasBecomeLps)
{
    const Plan plan = loadPlan(write("line.mrk.json", R"({
        "@schema": "https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/Markups/Resources/Schema/markups-schema-v1.0.3.json#",
        "markups": [
          {"type": "Fiducial", "coordinateSystem": "LPS", "controlPoints": [{"position": [0, 0, 0]}]},
          {"type": "Line", "name": "biopsy", "coordinateSystem": "RAS", "coordinateUnits": "mm",
           "controlPoints": [{"id": "1", "position": [10, 20, 30]}, {"id": "2", "position": [-5, -6, 7]}],
           "measurements": [{"name": "length", "value": 1.0}]}]})"));
    ASSERT_EQ(plan.paths.size(), 1u);
    EXPECT_EQ(plan.paths[0].name, "biopsy");
    EXPECT_TRUE(nearVec(plan.paths[0].entry, Vec3d(-10, -20, 30), 0.0));
    EXPECT_TRUE(nearVec(plan.paths[0].target, Vec3d(5, 6, 7), 0.0));
    test::expectRefused<ValueError>([](const auto& p) { loadPlan(p); },
        write("none.mrk.json", R"({"markups": [{"type": "Fiducial"}]})"), "markups");
}

/// Numbers written by nlohmann::json and read back: exact (shortest round trip).
constexpr double kExact = 0.0;

std::string reportRefusal(const std::string& json)
{
    try {
        (void)parsePlan(json, "r.json");
    } catch (const ValueError& e) {
        return e.what();
    }
    return "";
}

TEST(PlanReport, ReportPathsInRankOrder)
{
    // voxhap plan's report: only entry and target are read, path N is rank N.
    const Plan plan = parsePlan(
        R"({"schema": "voxhap-plan-report/1", "paths": [{"rank": 1, "entry": [40, -3.6, 0], "target": [5, -78, 0],
            "segments": [], "risk": {"total": 1}}, {"rank": 2, "entry": [1, 2, 3], "target": [4, 5, 6.5]}]})",
        "r.json");
    ASSERT_EQ(plan.paths.size(), 2u);
    EXPECT_EQ(plan.paths[0].name, "path 1");
    EXPECT_EQ(plan.paths[1].name, "path 2");
    EXPECT_TRUE(nearVec(plan.paths[0].entry, Vec3d(40, -3.6, 0), kExact));
    EXPECT_TRUE(nearVec(plan.paths[1].target, Vec3d(4, 5, 6.5), kExact));
    EXPECT_FALSE(plan.paths[0].needle);
    // A search that found nothing: a report without paths, read as a plan without paths.
    EXPECT_TRUE(parsePlan(R"({"schema": "voxhap-plan-report/1", "paths": []})", "r.json").paths.empty());
}

TEST(PlanReport, RefusalsNameTheField)
{
    EXPECT_NE(reportRefusal(R"({"schema": "other", "paths": []})").find("r.json: schema: must be"), std::string::npos);
    EXPECT_NE(reportRefusal(R"({"schema": "voxhap-plan-report/1"})").find("r.json: paths: must be an array"),
        std::string::npos);
    EXPECT_NE(reportRefusal(R"({"schema": "voxhap-plan-report/1", "paths": [{"entry": [0, 0], "target": [1, 1, 1]}]})")
                  .find("r.json: paths[0].entry: must be [x, y, z] in mm"),
        std::string::npos);
    EXPECT_NE(
        reportRefusal(R"({"schema": "voxhap-plan-report/1", "paths": [{"entry": [0, 0, 0], "target": [0, 0, 0]}]})")
            .find("r.json: paths[0]: entry and target coincide"),
        std::string::npos);
    EXPECT_NE(reportRefusal("{not json").find("r.json"), std::string::npos);
}

TEST_F(PlanFiles, TheThreeKindsAreToldApartByContentAndTheWrittenPlanReadsBack)
{
    const MarkupLine line{"a", Vec3d(1, 2, 3), Vec3d(4, 5, 6)};
    writeMarkups({line}, mDir / "paths.mrk.json");
    const Plan fromMarkups = loadPlan(mDir / "paths.mrk.json");
    ASSERT_EQ(fromMarkups.paths.size(), 1u);
    EXPECT_TRUE(nearVec(fromMarkups.paths[0].target, line.target, 1e-12)); // markups store %.17g-exact numbers
    const Plan fromReport = loadPlan(write(
        "report.json", R"({"schema": "voxhap-plan-report/1", "paths": [{"entry": [1, 2, 3], "target": [4, 5, 6]}]})"));
    ASSERT_EQ(fromReport.paths.size(), 1u);
    // What savePlan writes is voxhap-plan/1, and reads back the same.
    savePlan(fromReport, mDir / "plan.json");
    const Plan back = loadPlan(mDir / "plan.json");
    ASSERT_EQ(back.paths.size(), 1u);
    EXPECT_EQ(back.paths[0].name, "path 1");
    EXPECT_TRUE(nearVec(back.paths[0].entry, Vec3d(1, 2, 3), kExact));
    EXPECT_THROW(loadPlan(mDir / "missing.json"), IoError);
}

} // namespace
} // namespace voxhap::planning
