// SPDX-License-Identifier: Apache-2.0
/// @file Batch.cpp
/// @brief Manifests read, jobs run as child processes with their records, and
/// the cohort table (Batch.h).

#include "batch/Batch.h"

#include "core/AtomicFile.h"
#include "core/BoundedRead.h"
#include "core/Errors.h"
#include "core/JsonFields.h"
#include "core/Version.h"

#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <fcntl.h>
#include <fstream>
#include <iomanip>
#include <set>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace voxhap::batch {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

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

} // namespace

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

namespace {

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
int runChild(const fs::path& program, const std::vector<std::string>& argv, const fs::path& stdoutFile,
    const fs::path& stderrFile)
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
        ::execv(program.c_str(), cargv.data());
        ::_exit(127);
    }
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0) {
        if (errno != EINTR) throw IoError("cannot wait for a job");
    }
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

} // namespace

std::string jobStatus(const Manifest& m, const Job& job)
{
    const auto rec = jobRecord(m, job);
    // A record of an earlier version of the job (another fingerprint) does not count.
    return rec && rec->value("fingerprint", "") == fingerprint(job) ? rec->value("status", "not run") : "not run";
}

Json toJson(const JobOutcome& o)
{
    if (o.status == "kept")
        return {{"index", o.index}, {"id", o.id}, {"status", "kept"}, {"folder", o.folder.string()}};
    return {{"index", o.index}, {"id", o.id}, {"status", o.status}, {"exit_code", o.exitCode}, {"seconds", o.seconds},
        {"folder", o.folder.string()}, {"error", o.error}};
}

JobOutcome runJob(const Manifest& m, const Job& job, const fs::path& program, bool force,
    const std::function<void(const Job&)>& onStart)
{
    JobOutcome out;
    out.index = job.index;
    out.id = job.id;
    out.folder = jobDir(m, job);
    const fs::path& dir = out.folder;
    const std::string fp = fingerprint(job);
    if (!force) {
        if (const auto rec = jobRecord(m, job);
            rec && rec->value("status", "") == "done" && rec->value("fingerprint", "") == fp) {
            out.status = "kept";
            return out;
        }
    }
    // execv's failure would only show as exit code 127 in every job: say it once, first.
    if (program.empty() || ::access(program.c_str(), X_OK) != 0)
        throw IoError("voxhap batch: program: \"" + program.string() +
            "\" is not an executable file (the voxhap program runs each job)");
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
    if (onStart) onStart(job);
    const auto t0 = std::chrono::steady_clock::now();
    const int code = runChild(program, argv, temporaryPathFor(outFile), errFile);
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    out.exitCode = code;
    Json result;
    try {
        const std::string text = readBoundedFile(temporaryPathFor(outFile), "job output");
        if (!text.empty()) result = parseJsonText(text, outFile.string());
    } catch (const Error& e) {
        if (code == 0) out.error = e.what();
    }
    std::error_code ec;
    fs::remove(temporaryPathFor(outFile), ec);
    if (code != 0) {
        std::ifstream in(errFile);
        std::stringstream s;
        s << in.rdbuf();
        out.error = lastLine(s.str());
        if (out.error.empty()) out.error = "exit code " + std::to_string(code);
    }
    const bool ok = code == 0 && out.error.empty();
    out.status = ok ? "done" : "failed";
    Json rec{{"schema", "voxhap-batch-job/1"}, {"index", job.index}, {"id", job.id}, {"command", job.command},
        {"volume", job.volume}, {"phantom", job.phantom}, {"args", job.args}, {"fingerprint", fp},
        {"voxhap", std::string(kVersion)}, {"status", out.status}, {"exit_code", code}, {"seconds", out.seconds},
        {"error", out.error}, {"result", result}};
    OutputSet outputs; // the command's own summary and the record that says the job is finished, together
    if (!result.is_null())
        outputs.addStream(outFile, [&](std::ostream& o) { o << result.dump(2) << '\n'; });
    else
        outputs.remove(outFile);
    outputs.addStream(dir / "job.json", [&](std::ostream& o) { o << rec.dump(2) << '\n'; });
    outputs.commit();
    return out;
}

std::optional<int> selectedIndex(std::optional<int> option, const Manifest& m)
{
    std::optional<long> idx;
    std::string source = "--index";
    if (option && *option >= 0) {
        idx = *option;
    } else {
        for (const char* var : {"SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"}) {
            const char* v = std::getenv(var);
            if (!v || !*v) continue;
            char* end = nullptr;
            errno = 0;
            const long x = std::strtol(v, &end, 10);
            if (*end != '\0' || errno != 0 || x < 0)
                throw ValueError(std::string(var) + " is \"" + v + "\", not a job index (0 or more)");
            idx = x;
            source = var;
            break;
        }
    }
    if (!idx) return std::nullopt;
    const std::size_t count = m.jobs.size();
    if (*idx >= long(count))
        throw ValueError(source + " " + std::to_string(*idx) + " is past the last job of " + m.file.string() + " (" +
            std::to_string(count) + " jobs: 0 to " + std::to_string(count - 1) + ")");
    return int(*idx);
}

// The cohort table ------------------------------------------------------------

namespace {

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

} // namespace

MergeResult merge(const Manifest& m)
{
    std::vector<std::map<std::string, std::string>> rows;
    std::set<std::string> resultColumns;
    Json cohort{{"schema", "voxhap-batch-cohort/1"}, {"manifest", m.file.string()}, {"jobs", Json::array()}};
    MergeResult out;
    out.counts = {{"done", 0}, {"failed", 0}, {"not run", 0}};
    for (const Job& job : m.jobs) {
        std::map<std::string, std::string> row{{"index", std::to_string(job.index)}, {"id", job.id},
            {"command", job.command}, {"input", job.volume.empty() ? job.phantom : job.volume}};
        Json entry{{"index", job.index}, {"id", job.id}, {"command", job.command}};
        const auto rec = jobRecord(m, job);
        const std::string status = jobStatus(m, job);
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
        ++out.counts[status];
        rows.push_back(std::move(row));
        cohort["jobs"].push_back(std::move(entry));
    }
    cohort["counts"] = out.counts;
    std::vector<std::string> columns{"index", "id", "command", "input", "status", "seconds", "exit_code", "error"};
    columns.insert(columns.end(), resultColumns.begin(), resultColumns.end());
    fs::create_directories(m.output);
    out.csv = m.output / "cohort.csv";
    out.json = m.output / "cohort.json";
    OutputSet outputs;
    outputs.addStream(out.csv, [&](std::ostream& o) {
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
    outputs.addStream(out.json, [&](std::ostream& o) { o << cohort.dump(2) << '\n'; });
    outputs.commit();
    out.allDone = out.counts["done"] == int(m.jobs.size());
    return out;
}

} // namespace voxhap::batch
