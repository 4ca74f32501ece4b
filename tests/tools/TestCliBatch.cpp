// SPDX-License-Identifier: Apache-2.0
/// @file TestCliBatch.cpp
/// @brief `voxhap batch` as a scheduler runs it: a 4-job cohort run as four parallel
/// processes by index, then merged; jobs kept when done, run again when changed or
/// failed; the index from SLURM's and Kubernetes' variables; bad manifests refused in
/// one line naming the file and the field.

#include "common/CliRunner.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using voxhap::test::CliResult;
using voxhap::test::expectFailure;
using voxhap::test::expectUsageError;
using voxhap::test::slurp;

// Four jobs of the three kinds, on phantoms small enough for seconds: a path search on
// the torso, two simulated insertions (one on a phantom spec, one on the scene's own
// volume) and a segmentation.
const char* kManifest = R"({"schema": "voxhap-batch/1", "output": "cohort",
 "defaults": {"plan": ["--top", "2", "--step", "5", "--max-angle", "60", "--no-views"], "simulate": ["--no-plot"]},
 "jobs": [
  {"id": "torso-plan", "command": "plan", "volume": "torso.vdb", "args": ["--target", "5,-78,0"]},
  {"id": "lumbar-sim", "command": "simulate", "phantom": "lumbar:average", "args": ["--scene", "senac-average"]},
  {"id": "slab-seg", "command": "segment", "volume": "slab.vdb"},
  {"id": "conci-sim", "command": "simulate", "args": ["--scene", "conci"]}
 ]})";

class CliBatch : public voxhap::test::CliTest {
protected:
    void SetUp() override
    {
        CliTest::SetUp();
        write("m.json", kManifest);
    }
    void makePhantoms() const
    {
        ASSERT_EQ(run("phantom torso --spacing 1.5 -o torso.vdb").exitCode, 0);
        ASSERT_EQ(run("phantom slab --spacing 1 -o slab.vdb").exitCode, 0);
    }
    void write(const std::string& name, const std::string& text) const { std::ofstream(mDir / name) << text; }
    Json record(const std::string& id) const { return Json::parse(slurp(mDir / "cohort" / id / "job.json")); }
    std::vector<std::vector<std::string>> csv(const fs::path& p) const
    {
        std::vector<std::vector<std::string>> rows;
        std::istringstream in(slurp(p));
        for (std::string line; std::getline(in, line);) {
            std::vector<std::string> cells;
            std::istringstream l(line);
            for (std::string c; std::getline(l, c, ',');) cells.push_back(c);
            rows.push_back(cells);
        }
        return rows;
    }
};

TEST_F(CliBatch, FourIndexedProcessesThenMergeGiveOneCohortTable)
{
    makePhantoms();
    // Four processes at once, one per index, as an array job's tasks run.
    const std::string cmd = "cd '" + mDir.string() +
        "' && for i in 0 1 2 3; do '" VOXHAP_BINARY_DIR
        "/bin/voxhap' batch m.json --index $i >out.$i 2>err.$i & done; wait";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    for (const char* id : {"torso-plan", "lumbar-sim", "slab-seg", "conci-sim"}) {
        const Json rec = record(id);
        EXPECT_EQ(rec["status"], "done") << id << ": " << rec.dump();
        EXPECT_EQ(rec["exit_code"], 0) << id;
    }
    // Each job's outputs are the command's own, in its folder.
    EXPECT_TRUE(fs::exists(mDir / "cohort/torso-plan/report.json"));
    EXPECT_TRUE(fs::exists(mDir / "cohort/lumbar-sim/insertion.csv"));
    EXPECT_TRUE(fs::exists(mDir / "cohort/slab-seg/segmented.vdb"));
    EXPECT_EQ(record("torso-plan")["result"]["paths"][0]["target_tissue"], "lesion");

    const CliResult merged = run("batch merge m.json");
    ASSERT_EQ(merged.exitCode, 0) << merged.err;
    const auto rows = csv(mDir / "cohort/cohort.csv");
    ASSERT_EQ(rows.size(), 5u); // header and one row per job, in manifest order
    const auto& header = rows[0];
    const auto col = [&](const std::string& name) {
        const auto it = std::find(header.begin(), header.end(), name);
        EXPECT_NE(it, header.end()) << name;
        return std::size_t(it - header.begin());
    };
    const char* ids[] = {"torso-plan", "lumbar-sim", "slab-seg", "conci-sim"};
    for (std::size_t r = 1; r < rows.size(); ++r) {
        EXPECT_EQ(rows[r][col("index")], std::to_string(r - 1));
        EXPECT_EQ(rows[r][col("id")], ids[r - 1]);
        EXPECT_EQ(rows[r][col("status")], "done");
    }
    // The simulations' pop counts in the table are those of their own summaries.
    for (const std::size_t r : {std::size_t(2), std::size_t(4)}) {
        const Json own = Json::parse(slurp(mDir / "cohort" / ids[r - 1] / "stdout.json"));
        EXPECT_EQ(rows[r][col("result.pops")], own["pops"].dump());
    }
    const Json cohort = Json::parse(slurp(mDir / "cohort/cohort.json"));
    EXPECT_EQ(cohort["counts"]["done"], 4);
    EXPECT_EQ(cohort["jobs"].size(), 4u);
}

TEST_F(CliBatch, DoneJobsAreKeptChangedOrForcedOnesRunAgain)
{
    makePhantoms();
    ASSERT_EQ(run("batch m.json --index 2").exitCode, 0);
    const fs::path rec = mDir / "cohort/slab-seg/job.json";
    const auto before = fs::last_write_time(rec);
    // Rerun by SLURM's variable, then by Kubernetes': kept, the record untouched.
    const CliResult slurm = run("batch m.json", "SLURM_ARRAY_TASK_ID=2");
    ASSERT_EQ(slurm.exitCode, 0) << slurm.err;
    EXPECT_NE(slurm.out.find("slab-seg: done earlier, kept"), std::string::npos) << slurm.out;
    const CliResult k8s = run("batch m.json", "JOB_COMPLETION_INDEX=2");
    EXPECT_NE(k8s.out.find("slab-seg: done earlier, kept"), std::string::npos) << k8s.out;
    EXPECT_EQ(fs::last_write_time(rec), before);
    // --index wins over the variables.
    const CliResult both = run("batch m.json --index 2", "SLURM_ARRAY_TASK_ID=0");
    EXPECT_NE(both.out.find("slab-seg"), std::string::npos) << both.out;
    // --force runs it again.
    std::this_thread::sleep_for(std::chrono::milliseconds(20)); // a later modification time
    const CliResult forced = run("batch m.json --index 2 --force");
    EXPECT_EQ(forced.exitCode, 0);
    EXPECT_EQ(forced.out.find("kept"), std::string::npos) << forced.out;
    EXPECT_NE(fs::last_write_time(rec), before);
    // A changed job is not the one that ran: it shows as not run, then runs again.
    std::string changed = kManifest;
    const std::string seg = R"("volume": "slab.vdb"})";
    changed.replace(changed.find(seg), seg.size(), R"("volume": "slab.vdb", "args": ["--band", "10"]})");
    write("m.json", changed);
    const CliResult listed = run("batch list m.json --json");
    EXPECT_EQ(Json::parse(listed.out)[2]["status"], "not run") << listed.out;
    const CliResult again = run("batch m.json --index 2");
    EXPECT_EQ(again.out.find("kept"), std::string::npos) << again.out;
    EXPECT_EQ(record("slab-seg")["args"], Json::array({"--band", "10"}));
}

TEST_F(CliBatch, AFailedJobIsRecordedMergedAsFailedAndRunAgain)
{
    makePhantoms();
    std::string bad = kManifest;
    bad.replace(bad.find("torso.vdb"), 9, "missing.vdb");
    write("m.json", bad);
    const CliResult r = run("batch m.json --index 0");
    expectFailure(r, "torso-plan failed");
    EXPECT_NE(r.err.find("missing.vdb"), std::string::npos) << r.err; // the command's own one-line error
    EXPECT_EQ(record("torso-plan")["status"], "failed");
    // A folder without job.json is a job that never finished (killed): not run.
    fs::create_directories(mDir / "cohort/lumbar-sim");
    const CliResult merged = run("batch merge m.json --json");
    EXPECT_EQ(merged.exitCode, 1); // written, but not every job is done
    const Json cohort = Json::parse(slurp(mDir / "cohort/cohort.json"));
    EXPECT_EQ(cohort["jobs"][0]["status"], "failed");
    EXPECT_EQ(cohort["jobs"][1]["status"], "not run");
    EXPECT_EQ(cohort["counts"]["failed"], 1);
    EXPECT_EQ(cohort["counts"]["not run"], 3);
    // Fixed, the failed job runs again.
    write("m.json", kManifest);
    EXPECT_EQ(run("batch m.json --index 0").exitCode, 0);
    EXPECT_EQ(record("torso-plan")["status"], "done");
}

TEST_F(CliBatch, BadIndexesAndManifestsAreRefusedInOneLine)
{
    expectUsageError(run("batch m.json --index 4"), "past the last job of m.json (4 jobs: 0 to 3)");
    expectUsageError(run("batch m.json", "SLURM_ARRAY_TASK_ID=two"), "SLURM_ARRAY_TASK_ID is \"two\"");
    expectUsageError(run("batch m.json", "JOB_COMPLETION_INDEX=-1"), "JOB_COMPLETION_INDEX");
    const auto refused = [&](const std::string& text, const std::string& field) {
        write("bad.json", text);
        const CliResult r = run("batch bad.json --index 0");
        expectUsageError(r, "bad.json");
        EXPECT_NE(r.err.find(field), std::string::npos) << r.err;
    };
    const std::string head = R"({"schema": "voxhap-batch/1", "jobs": [)";
    refused(head +
            R"({"id": "a", "command": "plan", "volume": "t.vdb"}, {"id": "a", "command": "segment", "volume": "t.vdb"}]})",
        "jobs[1].id");
    refused(head + R"({"id": "../x", "command": "plan", "volume": "t.vdb"}]})", "jobs[0].id");
    refused(head + R"({"id": "a", "command": "serve", "volume": "t.vdb"}]})", "jobs[0].command");
    refused(head + R"({"id": "a", "command": "plan"}]})", "jobs[0].volume");
    refused(head + R"({"id": "a", "command": "plan", "volume": "t.vdb", "args": ["--out", "x"]}]})", "jobs[0].args");
    refused(head + R"({"id": "a", "command": "plan", "volume": "t.vdb", "colour": 1}]})", "jobs[0].colour");
    refused(R"({"schema": "voxhap-batch/1", "jobs": []})", "jobs");
    refused(R"({"schema": "voxhap-batch/2", "jobs": []})", "schema");
    refused("{\"schema\": ", "not valid JSON");
    EXPECT_FALSE(fs::exists(mDir / "bad-out")); // nothing written for a refused manifest
}

} // namespace
