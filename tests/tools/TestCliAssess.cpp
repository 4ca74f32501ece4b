// SPDX-License-Identifier: Apache-2.0
/// @file TestCliAssess.cpp
/// @brief `voxhap assess` as a user runs it (issue 23 item 3): a simulated cohort
/// (simulated hands, not trainees) written and assessed, careful simulated hands
/// passing with exit 0 and reckless ones flagged with exit 3, the classifier
/// trained with cross-validation and applied, serve's own metrics.json assessed,
/// and bad input refused in one line. Also `segment --labels totalsegmentator`
/// on a label map made by hand (issue 23 item 8).

#include "common/CliRunner.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

namespace {

namespace fs = std::filesystem;
using Result = voxhap::test::CliResult;
using voxhap::test::slurp;

class CliAssess : public voxhap::test::CliTest { };

TEST_F(CliAssess, SimulatedCohortIsAssessedTrainedAndClassified)
{
    const Result c = run("assess --simulate-cohort 3 --scene senac-average --out cohort --json");
    ASSERT_EQ(c.exitCode, 0) << c.err;
    EXPECT_EQ(nlohmann::json::parse(c.out)["simulated_cohort"]["sessions"], 6);
    ASSERT_TRUE(fs::exists(mDir / "cohort" / "labelled.csv"));
    EXPECT_NE(slurp(mDir / "cohort" / "labelled.csv").find("simulated"), std::string::npos);

    // A careful simulated hand passes every range: exit 0; a reckless one is flagged: exit 3.
    const Result careful = run("assess cohort/careful-01/metrics.json");
    EXPECT_EQ(careful.exitCode, 0) << careful.out << careful.err;
    EXPECT_NE(careful.out.find("0 with a flagged metric"), std::string::npos) << careful.out;
    const Result reckless = run("assess cohort/reckless-01/metrics.json --json");
    EXPECT_EQ(reckless.exitCode, 3) << reckless.err;
    const auto rj = nlohmann::json::parse(reckless.out);
    bool duraFlagged = false;
    for (const auto& m : rj["sessions"][0]["metrics"])
        duraFlagged = duraFlagged || (m["metric"] == "success_dura_intact" && m["verdict"] == "flag");
    EXPECT_TRUE(duraFlagged) << reckless.out;

    // The folder: every session, three of them flagged.
    const Result all = run("assess cohort --json");
    EXPECT_EQ(all.exitCode, 3);
    const auto aj = nlohmann::json::parse(all.out);
    EXPECT_EQ(aj["sessions"].size(), 6u);
    EXPECT_EQ(aj["flagged_sessions"], 3);

    // Train with 3-fold cross-validation, save, apply: reckless sessions get P(1) > 0.5.
    const Result t = run("assess --train cohort/labelled.csv --folds 3 --save-model model.json --json");
    ASSERT_EQ(t.exitCode, 0) << t.err;
    const auto tj = nlohmann::json::parse(t.out)["classifier"]["cross_validation"];
    EXPECT_EQ(tj["n"], 6);
    // The interval is Wilson's for the printed count, evaluated here from the formula
    // (z = 1.959964): centre (p + z²/2n)/(1 + z²/n), half-width z/(1 + z²/n)·sqrt(p(1−p)/n + z²/4n²).
    const double n = 6, k = tj["correct"].get<double>(), z = 1.959963984540054, p = k / n;
    EXPECT_EQ(tj["accuracy"].get<double>(), p);
    const double centre = (p + z * z / (2 * n)) / (1 + z * z / n);
    const double half = z / (1 + z * z / n) * std::sqrt(p * (1 - p) / n + z * z / (4 * n * n));
    EXPECT_NEAR(tj["ci95"][0].get<double>(), std::max(0.0, centre - half), 1e-12);
    EXPECT_NEAR(tj["ci95"][1].get<double>(), std::min(1.0, centre + half), 1e-12);
    ASSERT_TRUE(fs::exists(mDir / "model.json"));
    const Result m = run("assess cohort --model model.json --json");
    EXPECT_EQ(m.exitCode, 3);
    const auto mj = nlohmann::json::parse(m.out);
    for (const auto& s : mj["sessions"]) {
        const bool isReckless = s["file"].get<std::string>().find("reckless") != std::string::npos;
        EXPECT_EQ(s["classifier"]["predicted_label"], isReckless ? 1 : 0) << s["file"];
    }
}

// serve's metrics.json is what assess reads: a scripted 50 mm/s insertion through the
// dura is flagged on the dura and on the speed.
TEST_F(CliAssess, ServeMetricsAreAssessed)
{
    ASSERT_EQ(run("serve --scene senac-average --device sim --speed 50 --out served").exitCode, 0);
    const Result r = run("assess served --json");
    EXPECT_EQ(r.exitCode, 3) << r.err;
    std::set<std::string> flagged;
    const auto j = nlohmann::json::parse(r.out); // named: a loop over a temporary's member would dangle
    for (const auto& m : j["sessions"][0]["metrics"])
        if (m["verdict"] == "flag") flagged.insert(m["metric"].get<std::string>());
    EXPECT_TRUE(flagged.count("success_dura_intact"));
    EXPECT_TRUE(flagged.count("speed_mean_mm_per_s"));
}

TEST_F(CliAssess, BadInputIsOneLine)
{
    expectUsageError(run("assess"), "give sessions' metrics.json");
    expectUsageError(run("assess --save-model m.json x"), "--save-model needs --train");
    voxhap::test::expectFailure(run("assess nothing-here"), "nothing-here: no such file or folder");
    std::ofstream(mDir / "bad.json") << R"({"scene": "senac-average", "speed_mean_mm_per_s": "fast"})";
    voxhap::test::expectFailure(run("assess bad.json"), "bad.json: speed_mean_mm_per_s: must be a finite number");
    std::ofstream(mDir / "noscene.json") << R"({"scene": "my-own-scene", "pops": 2})";
    voxhap::test::expectFailure(run("assess noscene.json"), "noscene.json: scene: 'my-own-scene'");
    std::ofstream(mDir / "l.csv") << "label,speed\n1,2\n0,fast\n";
    voxhap::test::expectFailure(run("assess --train l.csv"), "l.csv: line 3: column 'speed': 'fast' is not a number");
}

// A TotalSegmentator-style multilabel map written by hand as NRRD: class 63
// (inferior_vena_cava) in a cube of 10 voxels a side labels vein; without --label-map the
// keyword is refused; a folder with a mask of an unknown name is refused naming it.
TEST_F(CliAssess, SegmentTakesTotalSegmentatorLabels)
{
    ASSERT_EQ(run("phantom torso --spacing 3 -o torso.vdb").exitCode, 0);
    {
        std::ofstream f(mDir / "total.nrrd", std::ios::binary);
        f << "NRRD0004\ntype: uint8\ndimension: 3\nspace: left-posterior-superior\nsizes: 10 10 10\n"
             "space directions: (3,0,0) (0,3,0) (0,0,3)\nspace origin: (60,-15,-15)\nencoding: raw\n\n";
        const std::string data(1000, char(63));
        f << data;
    }
    const Result r = run("segment torso.vdb --out seg.vdb --labels totalsegmentator --label-map total.nrrd --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    // Every imported voxel (those of the phantom's grid nearest the cube's) is vein.
    const auto imported = j["imported_voxels"].get<long>();
    EXPECT_GT(imported, 0);
    bool vein = false;
    for (const auto& l : j["labels"]) vein = vein || (l["name"] == "vein" && l["voxels"] == imported);
    EXPECT_TRUE(vein) << r.out;
    expectUsageError(run("segment torso.vdb --out s.vdb --labels totalsegmentator"), "needs --label-map");
    fs::create_directories(mDir / "masks");
    std::ofstream(mDir / "masks" / "liver_tumour.nii.gz") << "x";
    voxhap::test::expectFailure(run("segment torso.vdb --out s.vdb --labels totalsegmentator --label-map masks"),
        "liver_tumour.nii.gz: 'liver_tumour' is neither a class");
}

} // namespace
