// SPDX-License-Identifier: Apache-2.0
/// @file BatchBindings.cpp
/// @brief Python: voxhap.batch, the cohort runner of `voxhap batch`
/// (batch/Batch.h). Each job runs the voxhap program, which Python must name:
/// under Python the running program is python3, not voxhap.

#include "python/Bindings.h"

#include "batch/Batch.h"
#include "core/Errors.h"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <optional>
#include <string>

namespace voxhap::python {

namespace {

namespace fs = std::filesystem;

/// The program's path, refused in one line when it is not given.
fs::path requiredProgram(const std::optional<fs::path>& program)
{
    if (!program || program->empty())
        throw ValueError("voxhap.batch.run: program: the path of the voxhap executable is required (each job runs "
                         "it; Python's own program is python3)");
    return *program;
}

} // namespace

void bindBatch(py::module_& parent)
{
    py::module_ m = parent.def_submodule("batch",
        "Cohorts of plan, simulate and segment jobs from a manifest (schema voxhap-batch/1), each run by the voxhap "
        "program in a process of its own, as `voxhap batch` runs them (examples/cohort/README.md).");

    m.def(
        "run",
        [](const fs::path& manifest, const std::optional<fs::path>& program, std::optional<int> index, bool force) {
            const fs::path exe = requiredProgram(program);
            const batch::Manifest man = batch::loadManifest(manifest);
            const std::optional<int> selected = batch::selectedIndex(index, man);
            nlohmann::json runs = nlohmann::json::array();
            for (const batch::Job& job : man.jobs) {
                if (selected && job.index != *selected) continue;
                py::gil_scoped_release release; // the job is another process: let Python threads run meanwhile
                runs.push_back(batch::toJson(batch::runJob(man, job, exe, force)));
            }
            return toPython(runs);
        },
        py::arg("manifest"), py::arg("program") = py::none(), py::arg("index") = py::none(), py::arg("force") = false,
        "Run the manifest's jobs (or only job `index`; default: SLURM_ARRAY_TASK_ID, else JOB_COMPLETION_INDEX, "
        "else every job) with `program`, the voxhap executable (required). A job done earlier with the same "
        "command, input, arguments and version is kept unless `force`. Returns one dict per job run: index, id, "
        "status (done, failed or kept), exit_code, seconds, folder, error, as `voxhap batch --json` prints them.");

    m.def(
        "merge",
        [](const fs::path& manifest) {
            const batch::MergeResult r = batch::merge(batch::loadManifest(manifest));
            py::dict d;
            d["csv"] = r.csv;
            d["json"] = r.json;
            d["counts"] = r.counts;
            d["all_done"] = r.allDone;
            return d;
        },
        py::arg("manifest"),
        "Write OUTPUT/cohort.csv and cohort.json (one row per job) as `voxhap batch merge` does; returns the two "
        "paths, the counts of done, failed and not-run jobs, and whether every job is done.");

    m.def(
        "jobs",
        [](const fs::path& manifest) {
            const batch::Manifest man = batch::loadManifest(manifest);
            py::list out;
            for (const batch::Job& job : man.jobs) {
                py::dict d;
                d["index"] = job.index;
                d["id"] = job.id;
                d["command"] = job.command;
                d["status"] = batch::jobStatus(man, job);
                out.append(d);
            }
            return out;
        },
        py::arg("manifest"), "The manifest's jobs with their state (done, failed, not run), as `voxhap batch list`.");
}

} // namespace voxhap::python
