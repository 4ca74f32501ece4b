// SPDX-License-Identifier: Apache-2.0
/// @file CmdBatch.cpp
/// @brief `voxhap batch MANIFEST`: a cohort of plan, simulate and segment jobs, one
/// job per process, selected by index, so that a scheduler's array job (SLURM
/// `--array`, a Kubernetes Indexed Job) runs the cohort with no scheduler of
/// voxhap's own; `voxhap batch merge MANIFEST` writes one cohort table.
///
/// Each job runs the voxhap program itself as a child process (the same binary,
/// /proc/self/exe), so a job that crashes or runs out of memory cannot take the others
/// with it, and its outputs are exactly those of the command a user would type. A
/// job's folder gets job.json last, atomically: a folder without it is unfinished (a
/// killed job) and runs again; with it, the job is done (kept on a rerun, which makes
/// jobs idempotent) or failed (run again).
///
/// Exit codes: 0 every selected job done or kept (merge: the table written and every
/// job done), 1 a job failed (merge: the table written, some jobs failed or not run),
/// 2 a bad manifest or option, in one line naming the file and the field.

#include "tools/Cli.h"

#include "core/AtomicFile.h"
#include "core/BoundedRead.h"
#include "core/Errors.h"
#include "core/JsonFields.h"
#include "core/Version.h"

#include <nlohmann/json.hpp>

#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace voxhap::tools {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

struct Job {
    int index = 0;
    std::string id, command, volume, phantom;
    std::vector<std::string> args; ///< the manifest's defaults for the command, then the job's own
};

struct Manifest {
    fs::path file, output;
    std::vector<Job> jobs;
};

/// The commands a job may run, and the argument each one takes for its output.
const std::map<std::string, std::string>& jobCommands()
{
    static const std::map<std::string, std::string> c{{"plan", "--out"}, {"simulate", "--out"}, {"segment", "--out"}};
    return c;
}

bool validId(const std::string& id)
{
    if (id.empty() || id.size() > 128 || id == "." || id == "..") return false;
    for (const char c : id)
        if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.')) return false;
    return true;
}

std::vector<std::string> stringList(JsonFields& f, const std::string& key, const std::string& where)
{
    std::vector<std::string> out;
    if (!f.has(key)) return out;
    const Json& a = f.raw(key);
    if (!a.is_array()) f.fail(key, "must be an array of strings");
    for (const Json& s : a) {
        if (!s.is_string()) f.fail(key, "must be an array of strings");
        const std::string v = s.get<std::string>();
        // batch chooses where each job writes and reads its summary as JSON.
        if (v == "--out" || v == "-o" || v.rfind("--out=", 0) == 0 || v == "--json")
            f.fail(key, v + " is set by voxhap batch (" + where + ")");
        out.push_back(v);
    }
    return out;
}

Manifest loadManifest(const fs::path& file)
{
    Manifest m;
    m.file = file;
    const std::string origin = file.string();
    const Json j = JsonFields::readFile(file, "batch manifest");
    JsonFields f(j, origin, "");
    if (f.string("schema", "") != "voxhap-batch/1") f.fail("schema", "must be \"voxhap-batch/1\"");
    const fs::path base = file.parent_path().empty() ? fs::path(".") : file.parent_path();
    const std::string out = f.string("output", file.stem().string() + "-out");
    if (out.empty()) f.fail("output", "must not be empty");
    m.output = fs::path(out).is_absolute() ? fs::path(out) : base / out;
    std::map<std::string, std::vector<std::string>> defaults;
    if (f.has("defaults")) {
        JsonFields d(f.raw("defaults"), origin, "defaults");
        for (const auto& [cmd, flag] : jobCommands()) defaults[cmd] = stringList(d, cmd, "defaults." + cmd);
    }
    const Json& jobs = f.raw("jobs");
    if (!jobs.is_array() || jobs.empty()) f.fail("jobs", "must be a non-empty array");
    std::set<std::string> ids;
    for (std::size_t i = 0; i < jobs.size(); ++i) {
        const std::string where = "jobs[" + std::to_string(i) + "]";
        JsonFields jf(jobs[i], origin, where);
        Job job;
        job.index = int(i);
        job.id = jf.string("id", "");
        if (!validId(job.id))
            jf.fail("id", "must be 1-128 characters of A-Z a-z 0-9 . _ - (it names the job's folder)");
        if (!ids.insert(job.id).second) jf.fail("id", "\"" + job.id + "\" is used by an earlier job");
        job.command = jf.string("command", "");
        if (!jobCommands().count(job.command)) jf.fail("command", "must be plan, simulate or segment");
        const std::string volume = jf.string("volume", "");
        job.phantom = jf.string("phantom", "");
        if (!volume.empty() && !job.phantom.empty()) jf.fail("phantom", "give volume or phantom, not both");
        if (!job.phantom.empty() && job.command != "simulate") jf.fail("phantom", "only simulate takes a phantom");
        if (volume.empty() && job.command != "simulate") jf.fail("volume", "missing");
        if (!volume.empty()) job.volume = (fs::path(volume).is_absolute() ? fs::path(volume) : base / volume).string();
        job.args = defaults[job.command];
        for (std::string& a : stringList(jf, "args", where + ".args")) job.args.push_back(std::move(a));
        m.jobs.push_back(std::move(job));
    }
    return m;
}

/// What makes a job's outputs what they are: a finished job whose fingerprint
/// matches is kept; one whose command, input or arguments changed runs again.
std::string fingerprint(const Job& job)
{
    const Json j{{"command", job.command}, {"volume", job.volume}, {"phantom", job.phantom}, {"args", job.args},
        {"voxhap", std::string(kVersion)}};
    std::uint64_t h = 1469598103934665603ull; // FNV-1a, 64 bit
    for (const unsigned char c : j.dump()) h = (h ^ c) * 1099511628211ull;
    std::ostringstream s;
    s << std::hex << std::setw(16) << std::setfill('0') << h;
    return s.str();
}

fs::path jobDir(const Manifest& m, const Job& job) { return m.output / job.id; }

/// The job's record, when its folder holds one that parses.
std::optional<Json> jobRecord(const Manifest& m, const Job& job)
{
    const fs::path p = jobDir(m, job) / "job.json";
    std::error_code ec;
    if (!fs::is_regular_file(p, ec)) return std::nullopt;
    try {
        return readJsonFile(p, "job record");
    } catch (const Error&) {
        return std::nullopt; // unreadable: the job runs again and rewrites it
    }
}

std::string lastLine(const std::string& text)
{
    std::string t = text;
    while (!t.empty() && (t.back() == '\n' || t.back() == '\r')) t.pop_back();
    const auto nl = t.rfind('\n');
    return nl == std::string::npos ? t : t.substr(nl + 1);
}

/// Run `voxhap <command> …` for one job with stdout and stderr in files; returns the
/// exit code (128 + signal when the child was killed).
int runChild(const std::vector<std::string>& argv, const fs::path& stdoutFile, const fs::path& stderrFile)
{
    std::vector<char*> cargv;
    for (const std::string& a : argv) cargv.push_back(const_cast<char*>(a.c_str()));
    cargv.push_back(nullptr);
    const pid_t pid = ::fork();
    if (pid < 0) throw IoError("cannot start a job: fork failed");
    if (pid == 0) {
        const int out = ::open(stdoutFile.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        const int err = ::open(stderrFile.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        if (out < 0 || err < 0 || ::dup2(out, 1) < 0 || ::dup2(err, 2) < 0) ::_exit(126);
        ::execv("/proc/self/exe", cargv.data());
        ::_exit(127);
    }
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0) {
        if (errno != EINTR) throw IoError("cannot wait for a job");
    }
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

/// Run one job unless it is done with the same fingerprint. @return 0 done or kept, 1 failed
int runJob(const Manifest& m, const Job& job, bool force, bool json, Json& summary)
{
    const fs::path dir = jobDir(m, job);
    const std::string fp = fingerprint(job);
    if (!force) {
        if (const auto rec = jobRecord(m, job);
            rec && rec->value("status", "") == "done" && rec->value("fingerprint", "") == fp) {
            summary = {{"index", job.index}, {"id", job.id}, {"status", "kept"}, {"folder", dir.string()}};
            if (!json)
                std::cout << "job " << job.index << " " << job.id << ": done earlier, kept (" << dir.string() << ")\n";
            return 0;
        }
    }
    fs::create_directories(dir);
    fs::remove(dir / "job.json"); // running: the folder is unfinished until the new record is in place
    std::vector<std::string> argv{"voxhap", job.command};
    if (!job.volume.empty()) argv.push_back(job.volume);
    if (!job.phantom.empty()) argv.push_back(job.phantom);
    for (const std::string& a : job.args) argv.push_back(a);
    argv.push_back(jobCommands().at(job.command));
    argv.push_back(job.command == "segment" ? (dir / "segmented.vdb").string() : dir.string());
    argv.push_back("--json");
    const fs::path outFile = dir / "stdout.json", errFile = dir / "stderr.log";
    if (!json) std::cout << "job " << job.index << " " << job.id << ": voxhap " << job.command << " ..." << std::flush;
    const auto t0 = std::chrono::steady_clock::now();
    const int code = runChild(argv, temporaryPathFor(outFile), errFile);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    Json result;
    std::string error;
    try {
        const std::string text = readBoundedFile(temporaryPathFor(outFile), "job output");
        if (!text.empty()) result = parseJsonText(text, outFile.string());
    } catch (const Error& e) {
        if (code == 0) error = e.what();
    }
    std::error_code ec;
    fs::remove(temporaryPathFor(outFile), ec);
    if (code != 0) {
        std::ifstream in(errFile);
        std::stringstream s;
        s << in.rdbuf();
        error = lastLine(s.str());
        if (error.empty()) error = "exit code " + std::to_string(code);
    }
    const bool ok = code == 0 && error.empty();
    Json rec{{"schema", "voxhap-batch-job/1"}, {"index", job.index}, {"id", job.id}, {"command", job.command},
        {"volume", job.volume}, {"phantom", job.phantom}, {"args", job.args}, {"fingerprint", fp},
        {"voxhap", std::string(kVersion)}, {"status", ok ? "done" : "failed"}, {"exit_code", code},
        {"seconds", seconds}, {"error", error}, {"result", result}};
    OutputSet outputs; // the command's own summary and the record that says the job is finished, together
    if (!result.is_null())
        outputs.addStream(outFile, [&](std::ostream& o) { o << result.dump(2) << '\n'; });
    else
        outputs.remove(outFile);
    outputs.addStream(dir / "job.json", [&](std::ostream& o) { o << rec.dump(2) << '\n'; });
    outputs.commit();
    summary = {{"index", job.index}, {"id", job.id}, {"status", ok ? "done" : "failed"}, {"exit_code", code},
        {"seconds", seconds}, {"folder", dir.string()}, {"error", error}};
    if (!json) {
        std::cout << " " << (ok ? "done" : "failed") << " in " << std::fixed << std::setprecision(1) << seconds
                  << " s (" << dir.string() << ")\n";
    }
    if (!ok) std::cerr << "voxhap batch: job " << job.index << " " << job.id << " failed: " << error << '\n';
    return ok ? 0 : 1;
}

/// The job index from --index, else SLURM_ARRAY_TASK_ID, else JOB_COMPLETION_INDEX;
/// nothing: every job, in order.
std::optional<int> selectedIndex(int optionIndex, std::size_t jobCount, const fs::path& manifest)
{
    std::optional<long> idx;
    std::string source = "--index";
    if (optionIndex >= 0) {
        idx = optionIndex;
    } else {
        for (const char* var : {"SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"}) {
            const char* v = std::getenv(var);
            if (!v || !*v) continue;
            char* end = nullptr;
            errno = 0;
            const long x = std::strtol(v, &end, 10);
            if (*end != '\0' || errno != 0 || x < 0)
                throw UsageError(std::string(var) + " is \"" + v + "\", not a job index (0 or more)");
            idx = x;
            source = var;
            break;
        }
    }
    if (!idx) return std::nullopt;
    if (*idx >= long(jobCount))
        throw UsageError(source + " " + std::to_string(*idx) + " is past the last job of " + manifest.string() + " (" +
            std::to_string(jobCount) + " jobs: 0 to " + std::to_string(jobCount - 1) + ")");
    return int(*idx);
}

// The cohort table ------------------------------------------------------------

/// One row's columns from a job's JSON summary: objects by dotted keys, lists of
/// values joined by ';', lists of objects by their first element (with a .count).
void flatten(const Json& j, const std::string& prefix, std::map<std::string, std::string>& row)
{
    if (j.is_object()) {
        for (const auto& [k, v] : j.items()) flatten(v, prefix.empty() ? k : prefix + "." + k, row);
    } else if (j.is_array()) {
        const bool objects = !j.empty() && j.front().is_object();
        if (objects) {
            row[prefix + ".count"] = std::to_string(j.size());
            flatten(j.front(), prefix + ".0", row);
        } else {
            std::string cell;
            for (const Json& v : j)
                cell += (cell.empty() ? "" : ";") + (v.is_string() ? v.get<std::string>() : v.dump());
            row[prefix] = cell;
        }
    } else if (!j.is_null()) {
        row[prefix] = j.is_string() ? j.get<std::string>() : j.dump();
    }
}

std::string csvCell(const std::string& s)
{
    if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
    std::string q = "\"";
    for (const char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
}

int merge(const Manifest& m, bool json)
{
    std::vector<std::map<std::string, std::string>> rows;
    std::set<std::string> resultColumns;
    Json cohort{{"schema", "voxhap-batch-cohort/1"}, {"manifest", m.file.string()}, {"jobs", Json::array()}};
    std::map<std::string, int> counts{{"done", 0}, {"failed", 0}, {"not run", 0}};
    for (const Job& job : m.jobs) {
        std::map<std::string, std::string> row{{"index", std::to_string(job.index)}, {"id", job.id},
            {"command", job.command}, {"input", job.volume.empty() ? job.phantom : job.volume}};
        Json entry{{"index", job.index}, {"id", job.id}, {"command", job.command}};
        const auto rec = jobRecord(m, job);
        std::string status = "not run";
        if (rec && rec->value("fingerprint", "") == fingerprint(job))
            status = rec->value("status", "not run");
        else if (rec)
            status = "not run"; // a record of an earlier version of the job
        row["status"] = status;
        entry["status"] = status;
        if (rec && status != "not run") {
            row["seconds"] = Json((*rec)["seconds"]).dump();
            row["exit_code"] = Json((*rec)["exit_code"]).dump();
            row["error"] = rec->value("error", "");
            entry["seconds"] = (*rec)["seconds"];
            entry["error"] = (*rec)["error"];
            entry["result"] = (*rec)["result"];
            std::map<std::string, std::string> r;
            flatten((*rec)["result"], "", r);
            for (const auto& [k, v] : r) {
                row["result." + k] = v;
                resultColumns.insert("result." + k);
            }
        }
        ++counts[status];
        rows.push_back(std::move(row));
        cohort["jobs"].push_back(std::move(entry));
    }
    cohort["counts"] = counts;
    std::vector<std::string> columns{"index", "id", "command", "input", "status", "seconds", "exit_code", "error"};
    columns.insert(columns.end(), resultColumns.begin(), resultColumns.end());
    fs::create_directories(m.output);
    const fs::path csv = m.output / "cohort.csv", js = m.output / "cohort.json";
    OutputSet outputs;
    outputs.addStream(csv, [&](std::ostream& o) {
        for (std::size_t c = 0; c < columns.size(); ++c) o << (c ? "," : "") << csvCell(columns[c]);
        o << '\n';
        for (const auto& row : rows) {
            for (std::size_t c = 0; c < columns.size(); ++c) {
                const auto it = row.find(columns[c]);
                o << (c ? "," : "") << (it == row.end() ? "" : csvCell(it->second));
            }
            o << '\n';
        }
    });
    outputs.addStream(js, [&](std::ostream& o) { o << cohort.dump(2) << '\n'; });
    outputs.commit();
    if (json) {
        std::cout << Json{{"csv", csv.string()}, {"json", js.string()}, {"counts", counts}}.dump(2) << '\n';
    } else {
        std::cout << "voxhap batch merge: " << m.jobs.size() << " jobs: " << counts["done"] << " done, "
                  << counts["failed"] << " failed, " << counts["not run"] << " not run\n  " << csv.string() << "\n  "
                  << js.string() << '\n';
    }
    return counts["done"] == int(m.jobs.size()) ? 0 : kExitFailure;
}

int list(const Manifest& m, bool json)
{
    Json out = Json::array();
    for (const Job& job : m.jobs) {
        const auto rec = jobRecord(m, job);
        const std::string status =
            rec && rec->value("fingerprint", "") == fingerprint(job) ? rec->value("status", "not run") : "not run";
        out.push_back({{"index", job.index}, {"id", job.id}, {"command", job.command}, {"status", status}});
        if (!json)
            std::cout << std::setw(5) << job.index << "  " << std::left << std::setw(24) << job.id << std::setw(10)
                      << job.command << status << std::right << '\n';
    }
    if (json) std::cout << out.dump(2) << '\n';
    return 0;
}

struct BatchOptions {
    std::string manifest, mergeManifest, listManifest;
    int index = -1;
    bool force = false, json = false, mergeJson = false, listJson = false;
};

Manifest load(const std::string& file)
{
    try {
        return loadManifest(file);
    } catch (const Error& e) {
        throw UsageError(e.what()); // a bad manifest is a usage error: exit 2
    }
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
    return [o, cmd, mergeCmd, listCmd]() -> int {
        if (mergeCmd->parsed()) return merge(load(o->mergeManifest), o->mergeJson);
        if (listCmd->parsed()) return list(load(o->listManifest), o->listJson);
        if (o->manifest.empty())
            throw UsageError("a manifest is required (voxhap batch MANIFEST, or batch merge MANIFEST)");
        const Manifest m = load(o->manifest);
        const std::optional<int> index = selectedIndex(o->index, m.jobs.size(), m.file);
        Json runs = Json::array();
        int failed = 0;
        for (const Job& job : m.jobs) {
            if (index && job.index != *index) continue;
            Json summary;
            failed += runJob(m, job, o->force, o->json, summary);
            runs.push_back(std::move(summary));
        }
        if (o->json) std::cout << Json{{"manifest", m.file.string()}, {"jobs", runs}}.dump(2) << '\n';
        (void)cmd;
        return failed ? kExitFailure : 0;
    };
}

} // namespace voxhap::tools
