// SPDX-License-Identifier: Apache-2.0
/// @file TestMarkups.cpp
/// @brief Slicer markups: the fields the markups schema (v1.0.3) requires, a round
/// trip, RAS input, and one clear error per bad field.

#include "common/TempDirTest.h"
#include "core/Errors.h"
#include "planning/Markups.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

namespace voxhap::planning {
namespace {

const std::vector<MarkupLine> kLines{{"best", Vec3d(31.5, 1.25, -2.0), Vec3d(5.0, -78.0, 0.0)},
    {"second", Vec3d(-40.0, -3.0, 10.0), Vec3d(5.0, -78.0, 0.0)}};

TEST(Markups, HasTheFieldsSlicersSchemaRequires)
{
    const auto j = nlohmann::json::parse(markupsJson(kLines));
    // Slicer's markups-schema-v1.0.3.json: "required": ["@schema", "markups"] at the
    // top and ["type"] on each markup; coordinateSystem in {LPS, RAS}; coordinateUnits
    // "mm" or "um"; positionStatus in {undefined, preview, defined}.
    ASSERT_TRUE(j.contains("@schema"));
    EXPECT_NE(j["@schema"].get<std::string>().find("markups-schema-v1.0.3.json"), std::string::npos);
    ASSERT_TRUE(j["markups"].is_array());
    ASSERT_EQ(j["markups"].size(), kLines.size());
    for (const auto& m : j["markups"]) {
        EXPECT_EQ(m["type"], "Line");
        EXPECT_EQ(m["coordinateSystem"], "LPS");
        EXPECT_EQ(m["coordinateUnits"], "mm");
        ASSERT_EQ(m["controlPoints"].size(), 2u);
        for (const auto& cp : m["controlPoints"]) {
            ASSERT_TRUE(cp["position"].is_array());
            EXPECT_EQ(cp["position"].size(), 3u);
            EXPECT_TRUE(cp["id"].is_string());
            EXPECT_TRUE(cp["label"].is_string());
            EXPECT_EQ(cp["orientation"].size(), 9u);
            EXPECT_EQ(cp["positionStatus"], "defined");
        }
    }
}

class MarkupsFile : public test::TempDirTest { };

TEST_F(MarkupsFile, RoundTripsThroughAFile)
{
    const auto file = mDir / "paths.mrk.json";
    writeMarkups(kLines, file);
    const auto back = loadMarkups(file);
    ASSERT_EQ(back.size(), kLines.size());
    for (std::size_t i = 0; i < back.size(); ++i) {
        EXPECT_EQ(back[i].name, kLines[i].name);
        // Written with nlohmann's shortest round-trip doubles: read back exactly.
        EXPECT_EQ(back[i].entry, kLines[i].entry);
        EXPECT_EQ(back[i].target, kLines[i].target);
    }
}

TEST(Markups, RasInputIsConvertedToLps)
{
    const std::string text = R"({"@schema": "x", "markups": [{"type": "Fiducial", "controlPoints": []},
        {"type": "Line", "coordinateSystem": "RAS", "controlPoints": [{"position": [1, 2, 3]}, {"position": [-4, 5, 6]}]}]})";
    const auto lines = parseMarkups(text, "ras.mrk.json");
    ASSERT_EQ(lines.size(), 1u);
    EXPECT_EQ(lines[0].entry, Vec3d(-1, -2, 3));
    EXPECT_EQ(lines[0].target, Vec3d(4, -5, 6));
}

TEST(Markups, BadFieldsAreNamed)
{
    const auto message = [](const std::string& text) {
        try {
            parseMarkups(text, "bad.mrk.json");
        } catch (const ValueError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_NE(message("{").find("bad.mrk.json: not valid JSON"), std::string::npos);
    EXPECT_NE(message(R"({"markups": 3})").find("markups: must be an array"), std::string::npos);
    EXPECT_NE(
        message(R"({"markups": [{"type": "Line", "controlPoints": [{"position": [1, 2]}, {"position": [1, 2, 3]}]}]})")
            .find("markups[0].controlPoints[0].position"),
        std::string::npos);
    EXPECT_NE(message(R"({"markups": [{"type": "Line", "coordinateUnits": "um", "controlPoints": []}]})")
                  .find("coordinateUnits"),
        std::string::npos);
    EXPECT_NE(message(R"({"markups": [{"type": "Fiducial"}]})").find("no Line markup"), std::string::npos);
}

} // namespace
} // namespace voxhap::planning
