// SPDX-License-Identifier: Apache-2.0
/// @file Batch.h
/// @brief A cohort of plan, simulate and segment jobs from a manifest
/// (voxhap-batch/1), one job per process, selected by index, so that a
/// scheduler's array job (SLURM `--array`, a Kubernetes Indexed Job) runs the
/// cohort with no scheduler of voxhap's own; and the cohort table of their
/// results. `voxhap batch` and Python's voxhap.batch are its two callers.
///
/// Each job runs the voxhap program as a child process, started by the path the
/// caller gives (the program itself passes /proc/self/exe; under Python that is
/// python3, so Python must name the program), so that a job that crashes or runs
/// out of memory cannot take the others with it, and its outputs are exactly those
/// of the command a user would type. A job's folder gets job.json last,
/// atomically: a folder without it is unfinished (a killed job) and runs again;
/// with it, the job is done (kept on a rerun, which makes jobs idempotent) or
/// failed (run again).
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::batch {

/// @brief One job of a manifest.
struct Job {
    int index = 0;
    std::string id, command, volume, phantom;
    std::vector<std::string> args; ///< the manifest's defaults for the command, then the job's own
};

/// @brief A manifest read: where the jobs write (OUTPUT/<id>/) and the jobs in order.
struct Manifest {
    std::filesystem::path file, output;
    std::vector<Job> jobs;
};

/// @brief Read a voxhap-batch/1 manifest; relative paths are the manifest folder's.
/// @throw IoError if unreadable; ValueError naming the file and the field
Manifest loadManifest(const std::filesystem::path& file);

/// @brief What a job's outputs depend on (command, input, arguments, voxhap's
/// version), as 16 hex digits: a done job whose fingerprint matches is kept.
std::string fingerprint(const Job& job);

/// @brief The job @p m's folder holds it for: "done", "failed" or "not run"
/// (no record, or the record of a job whose fingerprint has changed).
std::string jobStatus(const Manifest& m, const Job& job);

/// @brief What running (or keeping) one job gave.
struct JobOutcome {
    int index = 0;
    std::string id;
    std::string status; ///< "done", "failed" or "kept" (done earlier with the same fingerprint)
    int exitCode = 0;   ///< the child's; 128 + signal when it was killed
    double seconds = 0.0;
    std::filesystem::path folder;
    std::string error; ///< the last line of the child's stderr, or why its output was unreadable
    bool ok() const { return status != "failed"; }
};

/// @brief The summary of one job as `voxhap batch --json` prints it.
nlohmann::json toJson(const JobOutcome& o);

/// @brief Run @p job with @p program (the voxhap executable) unless it is done
/// with the same fingerprint and @p force is off; @p onStart is called just
/// before the child starts (not for a kept job). Writes OUTPUT/<id>/stdout.json,
/// stderr.log and, last, job.json. @throw IoError when no process can be started
JobOutcome runJob(const Manifest& m, const Job& job, const std::filesystem::path& program, bool force = false,
    const std::function<void(const Job&)>& onStart = {});

/// @brief The job to run: @p option when set (≥ 0), else SLURM_ARRAY_TASK_ID, else
/// JOB_COMPLETION_INDEX; nothing means every job.
/// @throw ValueError for an index past the last job or a variable that is not one
std::optional<int> selectedIndex(std::optional<int> option, const Manifest& m);

/// @brief The cohort table merge wrote.
struct MergeResult {
    std::filesystem::path csv, json;
    std::map<std::string, int> counts; ///< "done", "failed", "not run"
    bool allDone = false;
};

/// @brief Write OUTPUT/cohort.csv (one row per job: index, id, command, input,
/// status, seconds, exit code, error and the job's JSON summary flattened to
/// dotted columns) and cohort.json, together. @throw IoError
MergeResult merge(const Manifest& m);

} // namespace voxhap::batch
