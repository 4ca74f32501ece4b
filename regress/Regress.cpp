// SPDX-License-Identifier: Apache-2.0
/// @file Regress.cpp
#include "regress/Regress.h"

#include "core/AtomicFile.h"
#include "core/Errors.h"
#include "core/Format.h"
#include "render/plots/Gnuplot.h"

#include <nlohmann/json.hpp>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <unistd.h>

namespace voxhap::regress {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

std::string sci(double v)
{
    std::ostringstream s;
    s << std::setprecision(3) << v;
    return s.str();
}

std::string xmlEscape(const std::string& in)
{
    std::string out;
    for (const char c : in) {
        switch (c) {
        case '&':
            out += "&amp;";
            break;
        case '<':
            out += "&lt;";
            break;
        case '>':
            out += "&gt;";
            break;
        case '"':
            out += "&quot;";
            break;
        case '\'':
            out += "&apos;";
            break;
        default:
            // XML 1.0 forbids most control characters, even escaped.
            if (static_cast<unsigned char>(c) >= 0x20 || c == '\n' || c == '\t') out += c;
        }
    }
    return out;
}

/// The explanation of a failing case, one line each: where it first failed,
/// in which tissue, and which recorded inputs changed.
std::vector<std::string> explanation(const CaseReport& c)
{
    std::vector<std::string> lines;
    if (!c.hasBaseline) lines.push_back("no baseline: run `voxhap regress --update` to record one");
    if (c.first) {
        std::string l = "first past tolerance at " + fixed(c.first->depthMm, 2) + " mm, in " + c.first->tissue +
            ", against the " + c.first->against;
        if (c.first->toleranceN > 0) l += ": |ΔF| " + sci(c.first->deltaN) + " N > " + sci(c.first->toleranceN) + " N";
        lines.push_back(l);
    }
    for (const auto& e : c.eventDiffs) lines.push_back("event: " + e);
    for (const auto& p : c.peakDiffs) lines.push_back(p);
    if (!c.measuredPass) lines.push_back("measured: " + c.measured + ": outside");
    if (c.hasBaseline) {
        if (c.inputDiffs.empty())
            lines.push_back("inputs: the same as the baseline's record (a change in voxhap's code, not in its data)");
        for (const auto& d : c.inputDiffs) lines.push_back("input: " + d);
    }
    if (!c.png.empty()) lines.push_back("plot: " + c.png);
    if (!c.plotProblem.empty()) lines.push_back("plot: not drawn: " + c.plotProblem);
    return lines;
}

} // namespace

std::size_t RegressResult::failed() const
{
    return std::size_t(std::count_if(cases.begin(), cases.end(), [](const CaseReport& c) { return !c.pass; }));
}

RegressResult runRegression(const Suite& suite, const RegressOptions& o)
{
    const auto t0 = std::chrono::steady_clock::now();
    RegressResult result;
    result.suite = suite.origin;
    result.threads = o.run.threads > 0 ? o.run.threads : tbb::info::default_concurrency();
    std::vector<std::size_t> selected;
    for (std::size_t i = 0; i < suite.cases.size(); ++i) {
        if (o.only.empty() || matchesPattern(suite.cases[i].name, o.only)) selected.push_back(i);
    }
    if (selected.empty()) throw ValueError("--only '" + o.only + "': matches no case of " + suite.origin);

    // Baselines are read before anything runs: a damaged one stops the run (exit 2)
    // unless --update is about to replace it.
    if (o.update) {
        // Where --update writes, refused in one line before anything runs.
        if (suite.compiledIn)
            throw IoError("--update: the built-in suite's baselines are compiled into this voxhap and its source "
                          "folder " +
                builtinSuiteDir().string() +
                " is not here; nothing written (run a copy of "
                "the suite as a file to keep baselines of your own)");
        std::error_code ec;
        const fs::path dir = fs::exists(suite.baselinesDir, ec) ? suite.baselinesDir : suite.baselinesDir.parent_path();
        if (::access((dir.empty() ? fs::path(".") : dir).c_str(), W_OK) != 0)
            throw IoError(
                "--update: " + fs::absolute(suite.baselinesDir, ec).string() + " is not writable; nothing written");
        result.updateDir = fs::absolute(suite.baselinesDir, ec).lexically_normal().string();
    }
    std::vector<std::optional<Baseline>> baselines;
    for (const std::size_t i : selected) {
        const std::string& name = suite.cases[i].name;
        try {
            if (suite.compiledIn) {
                const std::string* text = builtinRegressFile(name + ".json");
                baselines.push_back(text
                        ? std::optional<Baseline>(parseBaseline(*text, "builtin baseline " + name + ".json"))
                        : std::nullopt);
            } else {
                baselines.push_back(readBaseline(baselinePath(suite.baselinesDir, name)));
            }
        } catch (const Error& e) {
            if (!o.update) {
                // One line naming the suite, the case and the baseline's file and field.
                const std::string where = suite.origin + ": cases." + name + ".baseline: ";
                if (dynamic_cast<const IoError*>(&e)) throw IoError(where + e.what());
                throw ValueError(where + e.what());
            }
            baselines.emplace_back(std::nullopt);
        }
    }

    Runner runner(suite, selected, o.run);
    const std::vector<CaseRun> runs = runner.run();
    result.volumeSeconds = runner.volumeSeconds();
    result.volumes = runner.volumeCount();

    OutputSet writes;
    for (std::size_t k = 0; k < selected.size(); ++k) {
        const Case& c = suite.cases[selected[k]];
        CaseReport rep = compareCase(c, runs[k], baselines[k]);
        if (o.update) {
            const Baseline* b = baselines[k] ? &*baselines[k] : nullptr;
            const bool changed = !b || !rep.identical || !rep.inputDiffs.empty() || !rep.eventDiffs.empty() ||
                b->profile.samples.size() != runs[k].profile.samples.size() ||
                b->profile.envelope.size() != runs[k].profile.envelope.size();
            if (changed) {
                std::string what = !b                              ? "new baseline"
                    : rep.identical && b->profile.envelope.empty() ? "profile identical; envelope between samples added"
                    : rep.identical                                ? "profile identical"
                    : rep.pass ? "profile within tolerance (largest |ΔF| " + sci(rep.maxDeltaN) + " N)"
                               : "profile changed (largest |ΔF| " + sci(rep.maxDeltaN) + " N)";
                if (b && !rep.inputDiffs.empty())
                    what += "; inputs: " + rep.inputDiffs.front() +
                        (rep.inputDiffs.size() > 1 ? " and " + std::to_string(rep.inputDiffs.size() - 1) + " more"
                                                   : "");
                result.updated.push_back(c.name + ": " + what);
                const Json doc = baselineJson(c, runs[k]);
                writes.addStream(
                    baselinePath(suite.baselinesDir, c.name), [doc](std::ostream& out) { out << baselineText(doc); });
            }
        } else if (rep.pass && !o.plotDir.empty()) {
            // A plot left by an earlier run of a case that passes now would say it fails.
            std::error_code ec;
            fs::remove(o.plotDir / (c.name + ".png"), ec);
        } else if (!rep.pass && !o.plotDir.empty()) {
            std::vector<Sample> ref;
            std::string refName = "baseline";
            if (baselines[k]) {
                ref = baselines[k]->profile.samples;
            } else if (auto cf = closedForm(c, {}, runs[k].inputs, runs[k].profile.samples)) {
                refName = cf->rule;
                for (std::size_t i = 0; i < cf->modelN.size(); ++i)
                    ref.push_back({runs[k].profile.samples[i].depthMm, cf->modelN[i], cf->modelN[i], 0.0});
            }
            if (!ref.empty()) {
                fs::create_directories(o.plotDir);
                const std::string png = (o.plotDir / (c.name + ".png")).string();
                std::string why;
                if (plotCase(rep, runs[k], ref, refName, png, why))
                    rep.png = png;
                else
                    rep.plotProblem = why;
            }
        }
        result.cases.push_back(std::move(rep));
    }
    if (o.update) {
        fs::create_directories(suite.baselinesDir);
        writes.commit(); // each written, flushed and renamed; none half-written
    }
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return result;
}

void printReport(std::ostream& os, const RegressResult& r)
{
    os << "voxhap regress: " << r.suite << "\n\n";
    // The last column says which closed form of physics.md §7 each case was held
    // to, or why it has none: coverage that cannot vanish unseen.
    const auto eventsOf = [](const CaseReport& c) {
        std::string events = c.eventDiffs.empty() ? "same" : c.eventDiffs.front();
        if (c.eventDiffs.size() > 1) events += " (+" + std::to_string(c.eventDiffs.size() - 1) + ")";
        return events;
    };
    std::size_t w = 4, we = 6;
    for (const auto& c : r.cases) w = std::max(w, c.name.size()), we = std::max(we, eventsOf(c).size());
    os << std::left << std::setw(int(w)) << "case"
       << "  result  largest |ΔF| [N]  at [mm]  first past tol [mm]  " << std::setw(int(we)) << "events"
       << "  closed form\n";
    for (const auto& c : r.cases) {
        os << std::left << std::setw(int(w)) << c.name << "  " << std::setw(6)
           << (c.pass                 ? "pass"
                      : c.hasBaseline ? "FAIL"
                                      : "NEW")
           << "  " << std::setw(16) << sci(c.maxDeltaN) << "  " << std::setw(7) << fixed(c.maxDeltaDepthMm, 2) << "  "
           << std::setw(19) << (c.first ? fixed(c.first->depthMm, 2) : std::string("-")) << "  " << std::setw(int(we))
           << eventsOf(c) << "  " << c.closedForm << '\n';
    }
    // The literature's deflections, stated pass or fail (physics.md §9.2).
    for (const auto& c : r.cases) {
        if (!c.measured.empty()) os << "\ntip deviation of " << c.name << ": " << c.measured << '\n';
    }
    for (const auto& c : r.cases) {
        if (c.pass && c.inputDiffs.empty()) continue;
        os << '\n' << (c.pass ? "note " : "FAIL ") << c.name << " (" << c.reference << ")\n";
        if (c.pass) {
            os << "  inputs differ from the baseline's record, the profile does not:\n";
            for (const auto& d : c.inputDiffs) os << "    " << d << '\n';
            continue;
        }
        for (const auto& l : explanation(c)) os << "  " << l << '\n';
    }
    if (!r.updateDir.empty() && r.updated.empty()) os << "\nbaselines in " << r.updateDir << ": none changed\n";
    if (!r.updated.empty()) {
        os << "\nbaselines written to " << r.updateDir << ":\n";
        for (const auto& u : r.updated) os << "  " << u << '\n';
    }
    os << '\n'
       << r.cases.size() << " cases" << (r.updated.empty() ? "" : " (compared before the update)") << ": "
       << r.cases.size() - r.failed() << " passed, " << r.failed() << " failed, in " << fixed(r.seconds, 2) << " s on "
       << r.threads << " threads (" << r.volumes << " volumes built in " << fixed(r.volumeSeconds, 2)
       << " s); budget 10 s: " << (r.seconds <= 10.0 ? "within" : "OVER") << '\n';
}

nlohmann::json reportJson(const RegressResult& r)
{
    Json cases = Json::array();
    for (const auto& c : r.cases) {
        Json j{{"case", c.name}, {"pass", c.pass}, {"baseline", c.hasBaseline}, {"reference", c.reference},
            {"identical_to_baseline", c.identical}, {"digest", c.digest}, {"max_delta_N", c.maxDeltaN},
            {"max_delta_depth_mm", c.maxDeltaDepthMm}, {"event_differences", c.eventDiffs},
            {"peak_differences", c.peakDiffs}, {"input_differences", c.inputDiffs}, {"seconds", c.seconds}};
        j["closed_form_max_delta_N"] = c.closedFormMaxDeltaN ? Json(*c.closedFormMaxDeltaN) : Json(nullptr);
        j["closed_form"] = c.closedForm; // "closed form: R1" or "no closed form: <why>"
        if (c.tipDeviationMm) j["tip_deviation_mm"] = *c.tipDeviationMm;
        if (!c.measured.empty()) j["measured"] = {{"pass", c.measuredPass}, {"text", c.measured}};
        j["first_past_tolerance"] = c.first
            ? Json{{"depth_mm", c.first->depthMm}, {"delta_N", c.first->deltaN}, {"tolerance_N", c.first->toleranceN},
                  {"against", c.first->against}, {"tissue", c.first->tissue}}
            : Json(nullptr);
        j["explanation"] = c.pass ? Json::array() : Json(explanation(c));
        j["png"] = c.png.empty() ? Json(nullptr) : Json(c.png);
        cases.push_back(std::move(j));
    }
    return {{"suite", r.suite}, {"cases", cases}, {"passed", r.cases.size() - r.failed()}, {"failed", r.failed()},
        {"seconds", r.seconds}, {"volume_seconds", r.volumeSeconds}, {"volumes", r.volumes}, {"threads", r.threads},
        {"updated", r.updated}, {"update_dir", r.updateDir.empty() ? Json(nullptr) : Json(r.updateDir)}};
}

std::string junitXml(const RegressResult& r)
{
    std::ostringstream x;
    x << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<testsuites name=\"voxhap regress\" tests=\"" << r.cases.size() << "\" failures=\"" << r.failed()
      << "\" time=\"" << r.seconds << "\">\n"
      << "  <testsuite name=\"" << xmlEscape(r.suite) << "\" tests=\"" << r.cases.size() << "\" failures=\""
      << r.failed() << "\" errors=\"0\" time=\"" << r.seconds << "\">\n";
    for (const auto& c : r.cases) {
        x << "    <testcase classname=\"voxhap.regress\" name=\"" << xmlEscape(c.name) << "\" time=\"" << c.seconds
          << "\"";
        if (c.pass) {
            x << "/>\n";
            continue;
        }
        const auto lines = explanation(c);
        x << ">\n      <failure message=\"" << xmlEscape(lines.empty() ? "failed" : lines.front())
          << "\" type=\"regression\">";
        for (const auto& l : lines) x << xmlEscape(l) << '\n';
        x << "</failure>\n    </testcase>\n";
    }
    x << "  </testsuite>\n</testsuites>\n";
    return x.str();
}

bool plotCase(const CaseReport& report, const CaseRun& run, const std::vector<Sample>& reference,
    const std::string& referenceName, const std::string& pngFile, std::string& why)
{
    const render::PlotDir dir;
    const std::string data = (dir.path() / "profile.dat").string();
    double lo = 0, hi = 1;
    {
        std::ofstream o(data);
        o << std::setprecision(17);
        for (const Sample& s : run.profile.samples) {
            // The reference at this depth: the same grid, else the nearest stored depth.
            auto it = std::min_element(reference.begin(), reference.end(), [&](const Sample& a, const Sample& b) {
                return std::abs(a.depthMm - s.depthMm) < std::abs(b.depthMm - s.depthMm);
            });
            o << s.depthMm << ' ' << it->modelN << ' ' << s.modelN << ' ' << s.modelN - it->modelN << '\n';
            lo = std::min(lo, s.depthMm);
            hi = std::max(hi, s.depthMm);
        }
    }
    std::ostringstream g;
    g << "set multiplot layout 2,1 title \"" << report.name << ": reference (" << referenceName
      << ") and now\" noenhanced\n"
      << "set xrange [" << lo << ":" << hi << "]\nset grid\nset key top left\nset lmargin 12\n";
    // Tissue layers along the path, shaded alternately and named (both panels).
    int n = 0;
    for (const Band& b : run.layers) {
        if (b.startMm >= hi) continue;
        ++n;
        const double end = std::min(b.endMm, hi);
        g << "set object " << n << " rect from " << b.startMm << ", graph 0 to " << end
          << ", graph 1 behind fillstyle solid 0.15 noborder fillcolor rgb '" << (n % 2 ? "#4a90d9" : "#7bc47f")
          << "'\nset label " << n << " \"" << b.name << "\" at " << 0.5 * (b.startMm + end)
          << ", graph 0.96 right rotate by 90 font ',8' noenhanced\n";
    }
    if (report.first)
        g << "set arrow 1 from " << report.first->depthMm << ", graph 0 to " << report.first->depthMm
          << ", graph 1 nohead dashtype 2 linecolor rgb '#cc0000'\n";
    g << "set ylabel 'model force [N]'\nset format x ''\n"
      << "plot '" << data << "' using 1:2 with lines lw 2 title 'reference', '" << data
      << "' using 1:3 with lines lw 1.5 title 'now'\n"
      << "set format x '%g'\nset xlabel 'tip depth along the path [mm]'\nset ylabel 'now - reference [N]'\n"
      << "plot '" << data << "' using 1:4 with lines lw 1.5 linecolor rgb '#cc0000' title 'difference'\n"
      << "unset multiplot\n";
    return render::runGnuplot(dir, g.str(), pngFile, 1200, 900, why);
}

} // namespace voxhap::regress
