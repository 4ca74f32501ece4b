// SPDX-License-Identifier: Apache-2.0
/// @file CmdBatch.cpp
/// @brief `voxhap batch MANIFEST`, `batch merge MANIFEST` and `batch list
/// MANIFEST`: the options, the calls into batch/Batch.h (which says how jobs run
/// and are kept) with this program as every job's program, and the printing.
///
/// Exit codes: 0 every selected job done or kept (merge: the table written and every
/// job done), 1 a job failed (merge: the table written, some jobs failed or not run),
/// 2 a bad manifest or option, in one line naming the file and the field.

#include "tools/Cli.h"

#include "batch/Batch.h"
#include "core/Errors.h"

#include <nlohmann/json.hpp>

#include <iomanip>
#include <iostream>

namespace voxhap::tools {

namespace {

using Json = nlohmann::json;
using batch::Job;
using batch::Manifest;

/// Every job runs this very program (the voxhap the user typed).
constexpr const char* kSelf = "/proc/self/exe";

struct BatchOptions {
    std::string manifest, mergeManifest, listManifest;
    int index = -1;
    bool force = false, json = false, mergeJson = false, listJson = false;
};

Manifest load(const std::string& file)
{
    try {
        return batch::loadManifest(file);
    } catch (const Error& e) {
        throw UsageError(e.what()); // a bad manifest is a usage error: exit 2
    }
}

int runJobs(const BatchOptions& o)
{
    if (o.manifest.empty()) throw UsageError("a manifest is required (voxhap batch MANIFEST, or batch merge MANIFEST)");
    const Manifest m = load(o.manifest);
    std::optional<int> index;
    try {
        index = batch::selectedIndex(o.index >= 0 ? std::optional<int>(o.index) : std::nullopt, m);
    } catch (const ValueError& e) {
        throw UsageError(e.what()); // a bad index is a usage error: exit 2
    }
    Json runs = Json::array();
    int failed = 0;
    const auto onStart = [&](const Job& job) {
        if (!o.json)
            std::cout << "job " << job.index << " " << job.id << ": voxhap " << job.command << " ..." << std::flush;
    };
    for (const Job& job : m.jobs) {
        if (index && job.index != *index) continue;
        const batch::JobOutcome r = batch::runJob(m, job, kSelf, o.force, onStart);
        if (!o.json && r.status == "kept") {
            std::cout << "job " << job.index << " " << job.id << ": done earlier, kept (" << r.folder.string() << ")\n";
        } else if (!o.json) {
            std::cout << " " << r.status << " in " << std::fixed << std::setprecision(1) << r.seconds << " s ("
                      << r.folder.string() << ")\n";
        }
        if (!r.ok()) std::cerr << "voxhap batch: job " << job.index << " " << job.id << " failed: " << r.error << '\n';
        failed += r.ok() ? 0 : 1;
        runs.push_back(batch::toJson(r));
    }
    if (o.json) std::cout << Json{{"manifest", m.file.string()}, {"jobs", runs}}.dump(2) << '\n';
    return failed ? kExitFailure : 0;
}

int merge(const Manifest& m, bool json)
{
    batch::MergeResult r = batch::merge(m);
    if (json) {
        std::cout << Json{{"csv", r.csv.string()}, {"json", r.json.string()}, {"counts", r.counts}}.dump(2) << '\n';
    } else {
        std::cout << "voxhap batch merge: " << m.jobs.size() << " jobs: " << r.counts["done"] << " done, "
                  << r.counts["failed"] << " failed, " << r.counts["not run"] << " not run\n  " << r.csv.string()
                  << "\n  " << r.json.string() << '\n';
    }
    return r.allDone ? 0 : kExitFailure;
}

int list(const Manifest& m, bool json)
{
    Json out = Json::array();
    for (const Job& job : m.jobs) {
        const std::string status = batch::jobStatus(m, job);
        out.push_back({{"index", job.index}, {"id", job.id}, {"command", job.command}, {"status", status}});
        if (!json)
            std::cout << std::setw(5) << job.index << "  " << std::left << std::setw(24) << job.id << std::setw(10)
                      << job.command << status << std::right << '\n';
    }
    if (json) std::cout << out.dump(2) << '\n';
    return 0;
}

} // namespace

Action registerBatch(CLI::App& app)
{
    auto o = std::make_shared<BatchOptions>();
    CLI::App* cmd = app.add_subcommand("batch",
        "Run a cohort of plan, simulate and segment jobs from a manifest, one job per process and index (SLURM array "
        "jobs, Kubernetes Indexed Jobs); `batch merge` writes the cohort table");
    cmd->add_option("manifest", o->manifest, "Manifest JSON (schema voxhap-batch/1; examples/cohort/README.md)");
    cmd->add_option("--index", o->index,
           "Run only this job (0-based); default: SLURM_ARRAY_TASK_ID, else JOB_COMPLETION_INDEX, else every job")
        ->check(CLI::Range(0, 100000000));
    cmd->add_flag("--force", o->force, "Run the selected jobs again even when they are done");
    cmd->add_flag("--json", o->json, "Print one JSON summary of the jobs run on stdout");
    CLI::App* mergeCmd = cmd->add_subcommand("merge", "Write OUTPUT/cohort.csv and cohort.json: one row per job");
    mergeCmd->add_option("manifest", o->mergeManifest, "Manifest JSON")->required();
    mergeCmd->add_flag("--json", o->mergeJson, "Print the paths and counts as JSON");
    CLI::App* listCmd = cmd->add_subcommand("list", "List the jobs with their index and state");
    listCmd->add_option("manifest", o->listManifest, "Manifest JSON")->required();
    listCmd->add_flag("--json", o->listJson, "Print the list as JSON");
    cmd->footer("Manifest:\n"
                "  {\"schema\": \"voxhap-batch/1\", \"output\": \"cohort-out\",\n"
                "   \"defaults\": {\"plan\": [\"--top\", \"3\"]},\n"
                "   \"jobs\": [{\"id\": \"p001-plan\", \"command\": \"plan\", \"volume\": \"p001/ct\",\n"
                "             \"args\": [\"--target\", \"10,-40,5\"]}, ...]}\n"
                "Paths are relative to the manifest's folder. Job N writes OUTPUT/<id>/ (job.json last); a job\n"
                "done with the same command, input, arguments and voxhap version is kept on a rerun.\n"
                "Exit: 0 every selected job done, 1 a job failed, 2 a bad manifest or option.");
    return [o, mergeCmd, listCmd]() -> int {
        if (mergeCmd->parsed()) return merge(load(o->mergeManifest), o->mergeJson);
        if (listCmd->parsed()) return list(load(o->listManifest), o->listJson);
        return runJobs(*o);
    };
}

} // namespace voxhap::tools
