// SPDX-License-Identifier: Apache-2.0
/// @file TestCliSegment.cpp
/// @brief `voxhap segment` as a user runs it: a phantom in, labels, distance
/// fields and a Slicer label map out, an imported map applied; bad input refused
/// in one line with nothing left behind.

#include "common/CliRunner.h"
#include "common/SharedData.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <set>

namespace {

namespace fs = std::filesystem;
using Result = voxhap::test::CliResult;

class CliSegment : public voxhap::test::CliTest { };

TEST_F(CliSegment, PhantomToLabelsDistanceFieldsAndNrrd)
{
    ASSERT_EQ(run("phantom torso --spacing 1.5 -o torso.vdb").exitCode, 0);
    const Result r = run("segment torso.vdb --out seg.vdb --export labels.nrrd --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["method"], "ct");
    std::set<std::string> names;
    for (const auto& l : j["labels"]) names.insert(l["name"].get<std::string>());
    // The built-in table puts the kidney at 200 HU (contrast-enhanced parenchyma),
    // clear of the bone threshold: the CT rules find it.
    for (const char* n : {"skin", "fat", "muscle", "lung", "kidney", "aorta", "cortical_bone", "cancellous_bone"}) {
        EXPECT_TRUE(names.count(n)) << n;
    }
    EXPECT_EQ(j["distance_fields"], nlohmann::json({"sdf.lung", "sdf.kidney", "sdf.aorta"}));
    // The output opens again, with its distance fields, and the NRRD reads back as labels.
    const Result info = run("info seg.vdb --json");
    ASSERT_EQ(info.exitCode, 0) << info.err;
    EXPECT_NE(info.out.find("label"), std::string::npos);
    ASSERT_TRUE(fs::exists(mDir / "labels.nrrd"));

    // Re-import the exported map with a mapping that keeps every id but turns aorta (15)
    // into lesion: the imported labels win.
    nlohmann::json map = {
        {"schema", "voxhap.label-mapping/1"}, {"file", "labels.nrrd"}, {"labels", nlohmann::json::object()}};
    for (const auto& l : j["labels"]) {
        map["labels"][std::to_string(l["id"].get<int>())] =
            l["name"] == "aorta" ? "lesion" : l["name"].get<std::string>();
    }
    std::ofstream(mDir / "map.json") << map.dump();
    const Result imp = run("segment torso.vdb --out seg2.vdb --labels map.json --json");
    ASSERT_EQ(imp.exitCode, 0) << imp.err;
    const auto k = nlohmann::json::parse(imp.out);
    EXPECT_GT(k["imported_voxels"].get<long>(), 0);
    bool lesion = false, aorta = false;
    for (const auto& l : k["labels"]) {
        lesion = lesion || l["name"] == "lesion";
        aorta = aorta || l["name"] == "aorta";
    }
    EXPECT_TRUE(lesion);
    EXPECT_FALSE(aorta);
}

TEST_F(CliSegment, BadInputIsOneLineAndLeavesNoOutput)
{
    ASSERT_EQ(run("phantom slab --spacing 1 -o slab.vdb").exitCode, 0);
    voxhap::test::expectError(run("segment slab.vdb --out seg.nrrd"), 2, "--out");
    std::ofstream(mDir / "bad.json") << R"({"schema": "voxhap.label-mapping/1", "labels": {"1": "spleen"}})";
    voxhap::test::expectError(
        run("segment slab.vdb --out seg.vdb --labels bad.json --label-map slab.vdb"), 1, "labels.1");
    voxhap::test::expectError(run("segment missing.vdb --out seg.vdb"), 1, "missing.vdb");
    voxhap::test::expectError(run("segment slab.vdb --out seg.vdb --critical spleen"), 1, "spleen");
    EXPECT_FALSE(fs::exists(mDir / "seg.vdb"));
}

TEST_F(CliSegment, HeadMrIsLabelledWithinItsAnatomyAndSaysSo)
{
    // The shared MPRAGE (a head): the torso rules do not apply, and the
    // command says so; no vessel or organ class is invented.
    VOXHAP_REQUIRE_DIR(voxhap::test::mprageDir());
    const Result r = run("segment '" + voxhap::test::mprageDir().string() + "' --out head.vdb --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_FALSE(j["notes"].empty()) << r.out;
    EXPECT_LT(j["body_width_mm"].get<double>(), 240.0);
    EXPECT_EQ(j["torso_fraction"], 0.0);
    for (const auto& l : j["labels"]) {
        const std::string name = l["name"];
        EXPECT_TRUE(name == "skin" || name == "fat" || name == "soft_tissue") << name;
    }
    const Result text = run("segment '" + voxhap::test::mprageDir().string() + "' --out head2.vdb");
    ASSERT_EQ(text.exitCode, 0) << text.err;
    EXPECT_NE(text.out.find("note: "), std::string::npos) << text.out;
}

TEST_F(CliSegment, HelpExplainsTheOptions)
{
    const Result r = run("segment --help");
    EXPECT_EQ(r.exitCode, 0);
    for (const char* opt : {"--out", "--labels", "--label-map", "--export", "--critical", "--band"}) {
        EXPECT_NE(r.out.find(opt), std::string::npos) << opt;
    }
}

} // namespace
