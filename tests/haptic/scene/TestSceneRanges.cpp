// SPDX-License-Identifier: Apache-2.0
/// @file TestSceneRanges.cpp
/// @brief Scene numbers are refused outside their physical range, naming the
/// file and the field (issue 20 item 10). The ranges come from the table in
/// docs/scenes.md, so the document and the parser cannot drift apart: for every
/// row, a value just beyond each bound is refused, the bound itself accepted
/// (or refused, for an open bound).

#include "common/BuiltinTable.h"
#include "core/Errors.h"
#include "haptic/scene/Scene.h"
#include "volume/TissueTable.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace voxhap::haptic {
namespace {

using Json = nlohmann::json;

std::string slurp(const std::string& path)
{
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

struct RangeRow {
    std::string field;
    bool openLow = false;
    double lo = 0, hi = 0;
};

/// The rows of docs/scenes.md's "Numbers" table whose range is an interval.
std::vector<RangeRow> documentedRanges()
{
    const std::string doc = slurp(VOXHAP_SOURCE_DIR "/docs/scenes.md");
    const auto start = doc.find("## Numbers");
    const auto end = doc.find("\n## ", start + 1);
    std::istringstream table(doc.substr(start, end - start));
    const std::regex row(R"(^\| `([a-zA-Z0-9_.]+)` \| [^|]+ \| ([\[(])([-0-9.e+]+), ([-0-9.e+]+)\][^|]* \|)");
    std::vector<RangeRow> out;
    std::smatch m;
    for (std::string line; std::getline(table, line);) {
        if (!std::regex_search(line, m, row)) continue;
        out.push_back({m[1], m[2] == "(", std::stod(m[3]), std::stod(m[4])});
    }
    return out;
}

/// A complete scene (every block present) with room under the device's peak for
/// any continuous force in range.
Json baseScene()
{
    Json j = Json::parse(slurp(VOXHAP_SOURCE_DIR "/data/scenes/senac-average.json"));
    j["device"]["max_force_N"] = 100.0;
    j["volume"]["bmi"] = 25.0;
    return j;
}

/// @p j with @p field (dotted; TISSUE is "skin") set to @p value; a term given as
/// true becomes an object of parameters.
Json with(Json j, const std::string& field, double value)
{
    Json* node = &j;
    std::istringstream parts(field);
    std::vector<std::string> keys;
    for (std::string k; std::getline(parts, k, '.');) keys.push_back(k == "TISSUE" ? "skin" : k);
    for (std::size_t i = 0; i + 1 < keys.size(); ++i) {
        Json& next = (*node)[keys[i]];
        if (!next.is_object()) next = Json::object();
        node = &next;
    }
    (*node)[keys.back()] = value;
    if (keys.front() == "success") j["success"]["rule"] = "reach_target"; // the rule radius_mm belongs to
    return j;
}

std::string refusal(const Json& scene)
{
    try {
        (void)parseScene(scene.dump(), "ranges.json");
    } catch (const ValueError& e) {
        return e.what();
    }
    return "";
}

TEST(SceneRanges, EveryDocumentedRangeIsEnforcedNamingFileAndField)
{
    const std::vector<RangeRow> rows = documentedRanges();
    // The table has 36 rows of numbers; all but the two gauges are intervals. Fewer
    // parsed rows means the table's format changed under this test.
    ASSERT_GE(rows.size(), 30u);
    ASSERT_EQ(refusal(baseScene()), "") << "the base scene itself must load";
    for (const RangeRow& r : rows) {
        std::string field = r.field;
        if (field.rfind("overrides.TISSUE.", 0) == 0) field = "overrides.skin." + field.substr(17);
        const double step = std::max(1e-9, std::abs(r.hi) * 1e-6);
        const std::string above = refusal(with(baseScene(), r.field, r.hi + step));
        EXPECT_NE(above.find("ranges.json: " + field + ": must be in"), std::string::npos)
            << r.field << " above " << r.hi << ": '" << above << "'";
        EXPECT_EQ(refusal(with(baseScene(), r.field, r.hi)), "") << r.field << " = " << r.hi;
        const double below = r.openLow ? r.lo : r.lo - std::max(1e-9, std::abs(r.lo) * 1e-6);
        const std::string low = refusal(with(baseScene(), r.field, below));
        EXPECT_NE(low.find("ranges.json: " + field + ": must be in"), std::string::npos)
            << r.field << " at " << below << ": '" << low << "'";
        if (!r.openLow) {
            EXPECT_EQ(refusal(with(baseScene(), r.field, r.lo)), "") << r.field << " = " << r.lo;
        }
    }
}

// The values the issue found accepted, each refused in one line naming the field.
TEST(SceneRanges, TheValuesOnceAcceptedAreRefused)
{
    const auto expectRefused = [](const Json& j, const std::string& what) {
        const std::string e = refusal(j);
        EXPECT_NE(e.find(what), std::string::npos) << "'" << e << "' lacks '" << what << "'";
        EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    };
    expectRefused(
        with(baseScene(), "insertion.rate_Hz", 1e-9), "ranges.json: insertion.rate_Hz: must be in [1, 1e+06] Hz");
    expectRefused(with(baseScene(), "insertion.speed_mm_per_s", 1e300), "insertion.speed_mm_per_s: must be in");
    expectRefused(with(baseScene(), "device.max_force_N", 1e308), "device.max_force_N: must be in");
    expectRefused(with(with(baseScene(), "device.max_force_N", 3.0), "device.max_continuous_force_N", 5.0),
        "device.max_continuous_force_N: must not exceed max_force_N");
    expectRefused(with(baseScene(), "needle.gauge", 18.5), "needle.gauge: must be a whole gauge number");
}

// Needle bending (physics.md §9.1): the values a beam cannot take are refused in
// one line naming the key, and bending beside the lock or the pivot correction
// (§9.5) likewise. Each with an accepted neighbour as the control.
TEST(SceneRanges, BendingValuesAreRefusedNamingTheKey)
{
    const auto expectRefused = [](const Json& j, const std::string& what) {
        const std::string e = refusal(j);
        EXPECT_NE(e.find(what), std::string::npos) << "'" << e << "' lacks '" << what << "'";
        EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    };
    const Json base = baseScene(); // 18 G: OD 1.270 mm
    expectRefused(with(base, "needle.youngs_modulus_GPa", -193.0),
        "ranges.json: needle.youngs_modulus_GPa: must be in (0, 1000] GPa");
    expectRefused(with(base, "needle.youngs_modulus_GPa", 0.0), "ranges.json: needle.youngs_modulus_GPa: must be in");
    EXPECT_EQ(refusal(with(base, "needle.youngs_modulus_GPa", 193.0)), "");
    expectRefused(with(base, "needle.inner_diameter_mm", 1.27),
        "ranges.json: needle.inner_diameter_mm: must be below the outer diameter (1.270 mm for 18 G");
    expectRefused(with(base, "needle.inner_diameter_mm", 2.0), "ranges.json: needle.inner_diameter_mm: must be below");
    expectRefused(with(base, "needle.inner_diameter_mm", -0.1), "ranges.json: needle.inner_diameter_mm: must not be");
    EXPECT_EQ(refusal(with(base, "needle.inner_diameter_mm", 1.2)), "");
    for (const double angle : {0.0, 90.0, 135.0}) {
        expectRefused(
            with(base, "needle.bevel_angle_deg", angle), "ranges.json: needle.bevel_angle_deg: must be in (0, 90)");
    }
    expectRefused(with(base, "needle.bevel_angle_deg", -10.0), "ranges.json: needle.bevel_angle_deg: must not be");
    EXPECT_EQ(refusal(with(base, "needle.bevel_angle_deg", 89.9)), "");

    Json locked = base; // senac-average has the trajectory lock
    locked["terms"]["bending"] = true;
    expectRefused(locked, "ranges.json: terms.bending: cannot run beside \"lock\"");
    Json pivoted = Json::parse(slurp(VOXHAP_SOURCE_DIR "/data/scenes/kyung.json"));
    pivoted["terms"]["bending"] = true;
    expectRefused(pivoted, "ranges.json: terms.bending: replaces the pivot correction");
    pivoted["terms"].erase("pivot");
    EXPECT_EQ(refusal(pivoted), "") << "control: bending without the pivot";
}

// A scene without device or insertion block loads with the documented defaults and
// says so (the CLI prints these lines); a complete scene says nothing.
TEST(SceneRanges, LeftOutBlocksAreDefaultedAndSaid)
{
    Json j = baseScene();
    j.erase("device");
    j.erase("insertion");
    const Scene s = parseScene(j.dump(), "bare.json");
    ASSERT_EQ(s.defaulted.size(), 2u);
    EXPECT_NE(s.defaulted[0].find("\"touch\""), std::string::npos) << s.defaulted[0];
    EXPECT_EQ(s.device.maxForceN, 3.3); // docs/scenes.md: the touch preset
    EXPECT_EQ(s.speedMmPerS, 10.0);
    EXPECT_EQ(s.rateHz, 1000.0);
    EXPECT_EQ(s.approachMm, 5.0);
    EXPECT_TRUE(parseScene(baseScene().dump(), "full.json").defaulted.empty());
}

/// A copy of the shipped tissue table with one quantity of one tissue changed.
std::string tableWith(const std::string& tissue, const std::string& key, const Json& quantity)
{
    Json t = Json::parse(slurp(VOXHAP_SOURCE_DIR "/data/tissues.json"));
    for (Json& x : t["tissues"]) {
        if (x["name"] == tissue) x[key] = quantity;
    }
    return t.dump();
}

// The tissue table: a quantity beyond its kind's largest physical value is refused
// naming the tissue and the field, after unit conversion (1e5 mN is 100 N: accepted).
TEST(TissueRanges, QuantitiesBeyondThePhysicalRangeAreRefused)
{
    const auto refusedTable = [](const std::string& text) -> std::string {
        try {
            (void)volume::TissueTable::parse(text, "t.json");
        } catch (const ValueError& e) {
            return e.what();
        }
        return "";
    };
    const std::string big =
        refusedTable(tableWith("skin", "puncture_force", {{"value", 1e308}, {"unit", "N"}, {"source", "attack"}}));
    EXPECT_NE(big.find("tissue 'skin'"), std::string::npos) << big;
    EXPECT_NE(big.find("puncture_force"), std::string::npos) << big;
    EXPECT_NE(big.find("at most 100"), std::string::npos) << big;
    EXPECT_EQ(refusedTable(tableWith("skin", "puncture_force", {{"value", 1e5}, {"unit", "mN"}, {"source", "s"}})), "");
    EXPECT_NE(refusedTable(tableWith("skin", "t1_3T", {{"value", 11}, {"unit", "s"}, {"source", "s"}})).find("t1_3T"),
        std::string::npos);
}

} // namespace
} // namespace voxhap::haptic
