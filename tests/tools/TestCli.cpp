// SPDX-License-Identifier: Apache-2.0
/// @file TestCli.cpp
/// @brief The voxhap command line: exit codes, one-line errors, no partial
/// output, and the issue's acceptance check (overweight lumbar phantom layers).

#include "common/CliRunner.h"

#include "haptic/scene/Scene.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <sys/stat.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;

using Result = voxhap::test::CliResult;
using Cli = voxhap::test::CliTest;
using voxhap::Vec3d;
using voxhap::test::expectFailure;
using voxhap::test::expectUsageError;
using voxhap::test::slurp;

TEST_F(Cli, HelpExplainsTheCommands)
{
    const Result top = run("--help");
    EXPECT_EQ(top.exitCode, 0);
    for (const char* cmd : {"phantom", "info", "demo", "simulate"})
        EXPECT_NE(top.out.find(cmd), std::string::npos) << cmd;
    const Result phantom = run("phantom --help");
    EXPECT_EQ(phantom.exitCode, 0);
    for (const char* word : {"lumbar", "torso", "--preset", "--bmi", "--spacing", "--out"}) {
        EXPECT_NE(phantom.out.find(word), std::string::npos) << word;
    }
}

TEST_F(Cli, BadArgumentsExitTwoWithOneLine)
{
    const std::vector<std::pair<std::string, std::string>> cases{
        {"", "subcommand"},
        {"frobnicate", "frobnicate"},
        {"phantom", "kind"},
        {"phantom blob", "blob"},
        {"phantom slab --preset overweight", "--preset"},
        {"phantom lumbar --bmi 5", "bmi"},
        {"phantom lumbar --spacing 0,1,1", "--spacing"},
        {"phantom lumbar --spacing abc", "--spacing"},
        {"phantom lumbar --rotate 1,2", "--rotate"},
        {"phantom slab --layers skin:2,fat:x", "fat"},
        {"phantom lumbar --field 7", "--field"},
        {"info", "file"},
    };
    for (const auto& [args, fragment] : cases) {
        SCOPED_TRACE(args);
        expectUsageError(run(args), fragment);
    }
    EXPECT_TRUE(fs::is_empty(mDir)) << "a failed command left files behind";
}

TEST_F(Cli, BadFilesExitOneNamingTheFile)
{
    expectFailure(run("info missing.vdb"), "missing.vdb");
    std::ofstream(mDir / "garbage.vdb") << "garbage";
    expectFailure(run("info garbage.vdb"), "garbage.vdb");
    std::ofstream(mDir / "bad-tissues.json")
        << R"({"tissues": [{"id": 0, "name": "air", "colour": [0,0,0], "hu": {}}]})";
    expectFailure(run("phantom slab --tissues bad-tissues.json"), "bad-tissues.json");
    EXPECT_FALSE(fs::exists(mDir / "slab.vdb"));
    expectFailure(run("phantom slab --layers skin:2,nothing:3"), "nothing");
}

TEST_F(Cli, FailedWriteLeavesNoPartialOutput)
{
    expectFailure(run("phantom slab --out no-such-dir/slab.vdb"), "no-such-dir/slab.vdb");
    EXPECT_FALSE(fs::exists(mDir / "no-such-dir"));
}

TEST_F(Cli, OverweightLumbarLayersMatchPhysics)
{
    // The issue's acceptance check: phantom, then info, layer depths from physics.md:
    // [S19] Table I overweight: derma 3.0 cm (skin 2 mm [LP] + fat), epidural space 4 mm;
    // supraspinous 3 + interspinous 15 = [C-ui] 18 mm; flavum 7.4 mm [C-ui]; CSF 13 mm [LP].
    const Result made = run("phantom lumbar --preset overweight --spacing 1 --out x.vdb");
    ASSERT_EQ(made.exitCode, 0) << made.err;
    const Result info = run("info x.vdb --json");
    ASSERT_EQ(info.exitCode, 0) << info.err;
    const auto j = nlohmann::json::parse(info.out);
    const std::vector<std::tuple<std::string, double, double>> expected{
        {"skin", 0.0, 2.0},
        {"fat", 2.0, 30.0},
        {"supraspinous_ligament", 30.0, 33.0},
        {"interspinous_ligament", 33.0, 48.0},
        {"ligamentum_flavum", 48.0, 55.4},
        {"epidural_space", 55.4, 59.4},
        {"dura", 59.4, 60.4},
        {"csf", 60.4, 73.4},
    };
    ASSERT_TRUE(j.contains("layers"));
    ASSERT_GE(j["layers"].size(), expected.size());
    for (std::size_t n = 0; n < expected.size(); ++n) {
        const auto& [name, start, end] = expected[n];
        EXPECT_EQ(j["layers"][n]["tissue"], name);
        EXPECT_NEAR(j["layers"][n]["start_mm"].get<double>(), start, 1e-6); // analytic layers, bisection to 1e-9 mm
        EXPECT_NEAR(j["layers"][n]["end_mm"].get<double>(), end, 1e-6);
    }
    EXPECT_EQ(j["spacing_mm"][0], 1.0);
    EXPECT_GT(j["active_voxels"].get<double>(), 0.0);
    EXPECT_LT(j["active_voxels"].get<double>(), j["dense_voxels"].get<double>()); // air above the skin is inactive

    // The text form prints the same table.
    const Result text = run("info x.vdb");
    EXPECT_NE(text.out.find("ligamentum_flavum"), std::string::npos);
    EXPECT_NE(text.out.find("55.40"), std::string::npos);
}

TEST_F(Cli, DemoWritesItsOutputsAndSaysWhere)
{
    const Result r = run("demo --out demo-out --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    for (const char* f :
        {"torso-segmented.vdb", "plan/report.json", "plan/paths.mrk.json", "plan/views.png", "plan/force-depth.png",
            "insertion/insertion.csv", "insertion/summary.json", "insertion/force-depth.png"}) {
        EXPECT_TRUE(fs::exists(mDir / "demo-out" / f)) << f;
    }
    // The best path to the lesion keeps clear of every critical structure, and the
    // simulated insertion along it says the same: no breach.
    const auto& best = j["plan"]["paths"][0];
    EXPECT_GE(best["min_clearance_mm"].get<double>(), 5.0);
    for (const auto& w : best["warnings"]) EXPECT_NE(w["code"], "critical_breach");
    EXPECT_TRUE(j["insertion"]["critical_breach_mm"].is_null());
    // Plan and simulation read the same voxel cells: the tip meets the vertebral
    // body's shell where the plan's profile ends, to within 0.5 mm (50 servo ticks
    // at 10 mm/s; only the tick spacing separates them).
    ASSERT_TRUE(best["force"]["contact_mm"].is_number());
    EXPECT_NEAR(j["insertion"]["bone_contact_mm"].get<double>(), best["force"]["contact_mm"].get<double>(), 0.5);
}

} // namespace

namespace {

// `voxhap simulate` on the [LP] scene: its events at the table's depths (physics.md §4:
// skin ends at 7, dura at 35 mm of the table, which starts 5 mm out of the skin), the
// CSV with one row per 1 kHz tick, a PNG and a JSON summary, and nothing half-written.
TEST_F(Cli, SimulateWritesCsvPlotAndSummary)
{
    const Result r = run("simulate --scene lumbar-puncture --out sim");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("skin puncture       at 2.0 mm"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("dura puncture       at 30.0 mm"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("bone contact        at 43.0 mm"), std::string::npos) << r.out;
    std::ifstream csv(mDir / "sim" / "insertion.csv");
    std::string header, line;
    std::getline(csv, header);
    EXPECT_EQ(header, "t_s,depth_mm,speed_mm_per_s,fx_N,fy_N,fz_N,force_N,axial_model_N,plunger_N,state,layer,events");
    long rows = 0;
    while (std::getline(csv, line)) ++rows;
    EXPECT_EQ(rows, 2751); // from -5 to 49.99 mm at 20 mm/s: 2.7495 s, ticks 0..2750 (the last clamped to the end)
    std::ifstream png(mDir / "sim" / "force-depth.png", std::ios::binary);
    char magic[8] = {};
    png.read(magic, 8);
    EXPECT_EQ(std::string(magic + 1, 3), "PNG");
    const nlohmann::json s = nlohmann::json::parse(slurp(mDir / "sim" / "summary.json"));
    EXPECT_NEAR(s["dura_puncture_mm"].get<double>(), 30.0, 0.02);
    EXPECT_EQ(s["pops"].get<int>(), 3);
    for (const auto& e : fs::directory_iterator(mDir / "sim")) EXPECT_NE(e.path().extension(), ".part") << e.path();

    // A second run into the same folder without a plot (issue 20 item 9): the outputs
    // replace the first run's together, and the first run's plot does not stay
    // beside the new table as if it were its picture.
    const Result again = run("simulate --scene senac-average --out sim --no-plot");
    ASSERT_EQ(again.exitCode, 0) << again.err;
    EXPECT_FALSE(fs::exists(mDir / "sim" / "force-depth.png"));
    const nlohmann::json s2 = nlohmann::json::parse(slurp(mDir / "sim" / "summary.json"));
    EXPECT_EQ(s2["scene"].get<std::string>(), "senac-average");
    for (const auto& e : fs::directory_iterator(mDir / "sim"))
        EXPECT_EQ(e.path().filename().string().rfind(".tmp.", 0), std::string::npos) << e.path();
}

// A bending needle's summary holds its bent shaft at the end (reference.md "simulate").
// Checked against the geometry the summary states: the needle's 90 mm from hub to
// tip (the beam's nodes keep their spacing along the needle, so the polyline is
// longer by about L·θ²/2: under 0.1 mm for slopes under 0.04), and
// the tip's distance from the straight line equal to tip_deviation_mm. Control: a
// half turn at 20 mm ends the tip on the other side of where the unturned one ends.
TEST_F(Cli, SimulateABendingNeedleReportsItsShaft)
{
    const auto shaftOf = [&](const std::string& args) {
        const Result r = run("simulate --scene lumbar-puncture-bending --no-plot --json " + args);
        EXPECT_EQ(r.exitCode, 0) << r.err;
        const nlohmann::json s = nlohmann::json::parse(r.out);
        std::vector<Vec3d> shaft;
        for (const auto& p : s["bending"]["shaft"]) shaft.emplace_back(p[0], p[1], p[2]);
        return std::make_pair(shaft, s["bending"]["tip_deviation_mm"].get<double>());
    };
    {
        std::ofstream script(mDir / "straight.csv");
        script << "t_s,depth_mm,roll_deg\n0,-5,0\n1,40,0\n";
        std::ofstream turned(mDir / "turned.csv");
        turned << "t_s,depth_mm,roll_deg\n0,-5,0\n0.5,20,0\n0.6,20,180\n1.1,40,180\n";
    }
    const auto [shaft, deviation] = shaftOf("--script straight.csv --out bent");
    ASSERT_GE(shaft.size(), 2u);
    double length = 0;
    for (std::size_t i = 1; i < shaft.size(); ++i) length += (shaft[i] - shaft[i - 1]).norm();
    EXPECT_NEAR(length, 90.0, 0.1);
    const voxhap::haptic::SceneInstance inst(
        voxhap::haptic::loadScene("lumbar-puncture-bending"), nullptr, voxhap::volume::TissueTable::builtin());
    const Vec3d u = (inst.target() - inst.entry()).normalized(), off = shaft.back() - inst.entry();
    const Vec3d lateral = off - off.dot(u) * u;
    // The JSON keeps a double's 17 digits: only the projection's round-off remains.
    EXPECT_NEAR(lateral.norm(), deviation, 1e-9);
    // A floor far under the 2.8 mm guide chapter 10 gives at 40 mm in muscle; straight is 0.
    EXPECT_GT(deviation, 0.05) << "40 mm of a 22 G Quincke needle bends";

    const auto [turnedShaft, turnedDeviation] = shaftOf("--script turned.csv --out turned");
    ASSERT_GE(turnedShaft.size(), 2u);
    const Vec3d off2 = turnedShaft.back() - inst.entry();
    EXPECT_LT((off2 - off2.dot(u) * u).dot(lateral), lateral.squaredNorm())
        << "control: the half turn brings the tip back toward the line";
}

TEST_F(Cli, SimulateScriptedMotionAndBadInput)
{
    {
        std::ofstream s(mDir / "script.csv");
        s << "t_s,depth_mm\n0,-5\n1,8\n2,3\n";
    }
    const Result r = run("simulate --scene senac-average --script script.csv --out sim --no-plot --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const nlohmann::json s = nlohmann::json::parse(r.out);
    EXPECT_TRUE(s["skin_puncture_mm"].is_null()); // the derma tents to 8 mm, short of its 10 mm pop, and is released
    EXPECT_NEAR(s["final_depth_mm"].get<double>(), 3.0, 1e-9);

    {
        std::ofstream bad(mDir / "bad.csv");
        bad << "t_s,depth_mm\n0,-5\n1,eight\n";
    }
    expectFailure(run("simulate --scene senac-average --script bad.csv --out bad"), "bad.csv: line 3");
    expectFailure(run("simulate --scene no-such-scene"), "no-such-scene: no such scene file or built-in scene");
    expectUsageError(run("simulate --scene kyung --entry 1,2"), "--entry");
    expectUsageError(run("simulate --scene kyung --script script.csv --speed 3"), "--script");
    expectFailure(run("simulate missing.vdb --scene kyung"), "missing.vdb");
    EXPECT_FALSE(fs::exists(mDir / "bad" / "insertion.csv"));
}

} // namespace

namespace {

/// session.csv's data rows (no header, no comment) and its closing comment line.
struct SessionRows {
    std::vector<std::string> rows;
    std::string trailer;
};
SessionRows sessionRows(const fs::path& file)
{
    SessionRows out;
    std::ifstream in(file);
    std::string line;
    std::getline(in, line); // the header
    while (std::getline(in, line)) {
        if (line.rfind('#', 0) == 0)
            out.trailer = line;
        else
            out.rows.push_back(line);
    }
    return out;
}

// `voxhap serve` with a scripted device in real time: -5 to 60 mm at 50 mm/s (1.3 s) runs
// through the dura (41.4–42.4 mm, popping at 45.5 mm): the metrics say so, and the
// session and events files are complete.
TEST_F(Cli, ServeWritesSessionAndMetrics)
{
    const Result r = run("serve --scene senac-average --device sim --speed 50 --out served --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const nlohmann::json m = nlohmann::json::parse(r.out);
    EXPECT_FALSE(m["success_dura_intact"].get<bool>());
    // Counts that agree, not a rate (a loaded machine may lose ticks; timing is bench/'s):
    // every tick is a session row, none dropped, and the script ran to its end at 60 mm.
    const SessionRows session = sessionRows(mDir / "served" / "session.csv");
    EXPECT_EQ(m["ticks"].get<long>(), long(session.rows.size()));
    EXPECT_EQ(m["records"].get<long>(), long(session.rows.size()));
    EXPECT_EQ(m["dropped_records"].get<long>(), 0);
    // The closing comment states the same counts (issue 20 item 7).
    EXPECT_EQ(session.trailer,
        "# " + std::to_string(session.rows.size()) +
            " records written, 0 dropped (the servo loop's record queue was full; the tick went on)");
    ASSERT_FALSE(session.rows.empty());
    const std::string& last = session.rows.back();
    EXPECT_NE(last.find(",60,"), std::string::npos) << "the last row is not at 60 mm: " << last;
    const std::string events = slurp(mDir / "served" / "events.csv");
    EXPECT_NE(events.find("loss_of_resistance"), std::string::npos);
    EXPECT_NE(events.find("dura_puncture"), std::string::npos);
    EXPECT_TRUE(fs::exists(mDir / "served" / "session.csv"));
    EXPECT_TRUE(fs::exists(mDir / "served" / "metrics.json"));
    expectUsageError(run("serve --scene senac-average --device bogus"), "--device");
    expectFailure(run("serve --scene senac-average --device replay:none.csv"), "none.csv");
}

// --device is parsed before anything loads (issue 20 item 10): a port with trailing
// junk is refused, and it is the first thing said even when the scene does not exist.
TEST_F(Cli, ServeDeviceIsCheckedBeforeTheScene)
{
    expectUsageError(run("serve --scene senac-average --device igtl:28945junk"), "the port must be a number");
    expectUsageError(run("serve --scene senac-average --device igtl:+80"), "the port must be a number");
    expectUsageError(run("serve --scene senac-average --device igtl:70000"), "outside 1..65535");
    expectUsageError(run("serve --scene no-such-scene --device igtl:1x"), "--device 'igtl:1x'");
}

// A scene that leaves out device and insertion runs on the documented defaults and
// says so, one line each (docs/scenes.md); a bad number names the file and the field.
TEST_F(Cli, SceneDefaultsAreSaidAndRangesNamed)
{
    std::string text = slurp(std::string(VOXHAP_SOURCE_DIR) + "/data/scenes/senac-average.json");
    const auto cut = [&text](const std::string& key) {
        const auto at = text.find("\"" + key + "\"");
        const auto end = text.find('}', at);
        text.erase(at, end - at + 2); // the block and its comma
    };
    cut("insertion");
    cut("device");
    // The comma after "needle" now ends the object: drop it.
    const auto last = text.rfind(',');
    text.erase(last, 1);
    std::ofstream(mDir / "bare.json") << text;
    const Result r = run("simulate --scene bare.json --out bare");
    ASSERT_EQ(r.exitCode, 0) << r.err << "\n" << text;
    EXPECT_NE(r.err.find("voxhap: note: bare.json: no \"device\" given: the \"touch\" preset"), std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("voxhap: note: bare.json: no \"insertion\" given"), std::string::npos) << r.err;

    std::ofstream(mDir / "fast.json") << std::regex_replace(
        slurp(std::string(VOXHAP_SOURCE_DIR) + "/data/scenes/senac-average.json"), std::regex("\"rate_Hz\": 1000"),
        "\"rate_Hz\": 1e-9");
    expectFailure(
        run("simulate --scene fast.json --out fast"), "fast.json: insertion.rate_Hz: must be in [1, 1e+06] Hz");
}

} // namespace

namespace {

// Ctrl-C stops the servo loop cleanly: exit 0, the session and metrics written, and
// the metrics say the run was interrupted.
TEST_F(Cli, ServeStopsCleanlyOnInterrupt)
{
    // The interrupt follows the readiness line, not a fixed delay that a loaded
    // machine may not honour. The deadline only keeps a broken serve from hanging the suite.
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        if (::chdir(mDir.c_str()) != 0) ::_exit(126);
        if (!std::freopen("out.json", "w", stdout) || !std::freopen("err.txt", "w", stderr)) ::_exit(126);
        ::execl(VOXHAP_BINARY_DIR "/bin/voxhap", "voxhap", "serve", "--scene", "senac-average", "--out", "stopped",
            "--json", static_cast<char*>(nullptr));
        ::_exit(127);
    }
    constexpr auto kDeadline = std::chrono::seconds(120);
    const auto start = std::chrono::steady_clock::now();
    bool ready = false;
    while (!ready && std::chrono::steady_clock::now() - start < kDeadline) {
        ready = slurp(mDir / "err.txt").find("voxhap serve: running") != std::string::npos;
        if (!ready) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ::kill(pid, SIGINT);
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(ready) << "no readiness line: " << slurp(mDir / "err.txt");
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0) << slurp(mDir / "err.txt");
    const nlohmann::json m = nlohmann::json::parse(slurp(mDir / "stopped" / "metrics.json"));
    EXPECT_TRUE(m["interrupted"].get<bool>());
    EXPECT_TRUE(fs::exists(mDir / "stopped" / "session.csv"));
    EXPECT_FALSE(fs::exists(mDir / "stopped" / "session.csv.part"));
    // The force was released before the session was written: the last force sent is zero.
    const SessionRows session = sessionRows(mDir / "stopped" / "session.csv");
    ASSERT_FALSE(session.rows.empty());
    const std::string& last = session.rows.back();
    std::vector<std::string> fields;
    std::stringstream row(last);
    for (std::string f; std::getline(row, f, ',');) fields.push_back(f);
    ASSERT_GE(fields.size(), 10u) << last;
    EXPECT_EQ(std::stod(fields[7]), 0.0) << last; // fx_N
    EXPECT_EQ(std::stod(fields[8]), 0.0) << last; // fy_N
    EXPECT_EQ(std::stod(fields[9]), 0.0) << last; // fz_N
}

/// Issue 20 item 4: every file the CLI reads (volumes, scenes, tissue tables,
/// label mappings, markups, insertion scripts) is refused in one line when it
/// is a FIFO, a device or, for text inputs, beyond the 16 MiB limit; nothing
/// opens a FIFO with no writer (each run is bounded by `timeout`, and a hang
/// shows as exit 124).
TEST_F(Cli, FifosDevicesAndHugeInputsAreRefusedWithoutHanging)
{
    ASSERT_EQ(::mkfifo((mDir / "fifo").c_str(), 0600), 0);
    const std::string bounded = "timeout 60";
    const auto refused = [&](const std::string& args, const std::string& fragment) {
        SCOPED_TRACE(args);
        expectFailure(run(args, bounded), fragment);
    };
    refused("info /dev/zero", "/dev/zero: file type: a character device");
    refused("info /dev/urandom", "/dev/urandom: file type: a character device");
    refused("info fifo", "fifo: file type: a FIFO");
    refused("convert fifo out.vdb", "fifo: file type: a FIFO");
    refused("simulate --scene /dev/zero", "/dev/zero: file type: a character device");
    refused("simulate --scene fifo", "fifo: file type: a FIFO");
    refused("simulate fifo --scene kyung", "fifo: file type: a FIFO");
    refused("simulate --scene kyung --tissues fifo", "fifo: file type: a FIFO");
    refused("simulate --scene kyung --tissues /dev/zero", "/dev/zero: file type: a character device");
    refused("simulate --scene kyung --script fifo", "fifo: file type: a FIFO");
    refused("plan missing.vdb --entries fifo", "fifo: file type: a FIFO");
    refused("plan missing.vdb --entries /dev/zero", "/dev/zero: file type: a character device");
    refused("segment missing.vdb --labels fifo --out labelled.vdb", "fifo: file type: a FIFO");
    refused("info fifo.mha", "no such file"); // a name alone is not a file
    fs::create_symlink("/dev/zero", mDir / "zero.nii");
    refused("info zero.nii", "zero.nii: file type: a character device");
    {
        std::ofstream big(mDir / "big.json");
        big << "{" << std::string((16u << 20), ' ') << "}";
    }
    refused("simulate --scene big.json", "big.json: size: 16777218 bytes, beyond the 16 MiB limit of a scene file");
    refused("info --tissues big.json missing.vdb", "big.json: size:");
}

} // namespace
