// SPDX-License-Identifier: Apache-2.0
/// @file Compare.cpp
#include "regress/Compare.h"

#include "core/Errors.h"
#include "core/Format.h"
#include "core/JsonFields.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <map>

namespace voxhap::regress {

namespace {

using Json = nlohmann::json;

/// The layer at @p depth along the path.
std::string tissueAt(const std::vector<Band>& layers, double depth)
{
    for (const Band& b : layers) {
        if (depth >= b.startMm && depth < b.endMm) return b.name;
    }
    return "outside the body";
}

/// Linear interpolation of @p ref's samples at @p depth (profiles of a
/// constant-speed insertion are monotonic in depth).
Sample sampleAt(const std::vector<Sample>& ref, double depth)
{
    if (ref.empty()) return {};
    auto it = std::lower_bound(ref.begin(), ref.end(), depth, [](const Sample& s, double d) { return s.depthMm < d; });
    if (it == ref.begin()) return ref.front();
    if (it == ref.end()) return ref.back();
    const Sample& b = *it;
    const Sample& a = *(it - 1);
    const double w = b.depthMm > a.depthMm ? (depth - a.depthMm) / (b.depthMm - a.depthMm) : 0.0;
    return {depth, a.modelN + w * (b.modelN - a.modelN), a.renderedN + w * (b.renderedN - a.renderedN),
        a.plungerN + w * (b.plungerN - a.plungerN)};
}

/// The envelope's columns in a baseline: the extremes of the ticks each sample stands for.
const char* const kEnvelopeKeys[6] = {
    "model_min_N", "model_max_N", "rendered_min_N", "rendered_max_N", "plunger_min_N", "plunger_max_N"};

std::vector<double> numbers(const JsonFields::Json& j, JsonFields& f, const std::string& key)
{
    if (!j.is_array()) f.fail(key, "must be a list of numbers");
    std::vector<double> out;
    out.reserve(j.size());
    for (const Json& v : j) {
        if (!v.is_number()) f.fail(key, "must be a list of numbers");
        out.push_back(v.get<double>());
    }
    return out;
}

} // namespace

std::filesystem::path baselinePath(const std::filesystem::path& dir, const std::string& name)
{
    return dir / (name + ".json");
}

nlohmann::json baselineJson(const Case& c, const CaseRun& run)
{
    Json inputs = Json::object();
    for (const auto& [k, v] : run.inputs) {
        if (v.number)
            inputs[k] = v.unit.empty() ? Json(*v.number) : Json{{"value", *v.number}, {"unit", v.unit}};
        else
            inputs[k] = v.text;
    }
    Json depth = Json::array(), model = Json::array(), rendered = Json::array(), plunger = Json::array();
    for (const Sample& s : run.profile.samples) {
        depth.push_back(s.depthMm);
        model.push_back(s.modelN);
        rendered.push_back(s.renderedN);
        plunger.push_back(s.plungerN);
    }
    Json env[6] = {Json::array(), Json::array(), Json::array(), Json::array(), Json::array(), Json::array()};
    for (const Envelope& e : run.profile.envelope) {
        const double v[6] = {e.modelMin, e.modelMax, e.renderedMin, e.renderedMax, e.plungerMin, e.plungerMax};
        for (int k = 0; k < 6; ++k) env[k].push_back(v[k]);
    }
    Json events = Json::array();
    for (const EventRecord& e : run.profile.events) events.push_back({{"event", e.event}, {"depth_mm", e.depthMm}});
    return {{"schema", "voxhap-regress-baseline/1"}, {"case", c.name},
        {"note", "reference output of `voxhap regress`; regenerate with `voxhap regress --update`"}, {"inputs", inputs},
        {"digest", run.profile.digest}, {"peak_model_N", run.profile.peakModelN},
        {"peak_rendered_N", run.profile.peakRenderedN}, {"events", events},
        {"profile",
            {{"depth_mm", depth}, {"model_N", model}, {"rendered_N", rendered}, {"plunger_N", plunger},
                {kEnvelopeKeys[0], env[0]}, {kEnvelopeKeys[1], env[1]}, {kEnvelopeKeys[2], env[2]},
                {kEnvelopeKeys[3], env[3]}, {kEnvelopeKeys[4], env[4]}, {kEnvelopeKeys[5], env[5]}}}};
}

std::string baselineText(const nlohmann::json& doc)
{
    std::string out = "{";
    const char* sep = "\n";
    for (const auto& [k, v] : doc.items()) {
        out += sep + std::string(" ") + Json(k).dump() + ": ";
        if (v.is_object()) {
            out += "{";
            const char* inner = "\n";
            for (const auto& [k2, v2] : v.items()) {
                out += inner + std::string("  ") + Json(k2).dump() + ": " + v2.dump();
                inner = ",\n";
            }
            out += "\n }";
        } else {
            out += v.dump();
        }
        sep = ",\n";
    }
    return out + "\n}\n";
}

namespace {

Baseline baselineFromJson(const Json& doc, const std::string& origin)
{
    return JsonFields::guarded(origin, [&] {
        JsonFields top(doc, origin, "");
        if (top.string("schema", "") != "voxhap-regress-baseline/1")
            top.fail("schema", "must be \"voxhap-regress-baseline/1\"");
        Baseline b;
        b.file = origin;
        top.string("case", "");
        top.string("note", "");
        b.profile.digest = top.string("digest", "");
        b.profile.peakModelN = top.number("peak_model_N", 0.0);
        b.profile.peakRenderedN = top.number("peak_rendered_N", 0.0);
        const Json& inputs = top.raw("inputs");
        if (!inputs.is_object()) top.fail("inputs", "must be an object");
        for (const auto& [k, v] : inputs.items()) {
            InputValue iv;
            if (v.is_number()) {
                iv.number = v.get<double>();
            } else if (v.is_object() && v.contains("value") && v["value"].is_number() && v.contains("unit") &&
                v["unit"].is_string()) {
                iv.number = v["value"].get<double>();
                iv.unit = v["unit"].get<std::string>();
            } else if (v.is_string()) {
                iv.text = v.get<std::string>();
            } else {
                top.fail("inputs." + k, "must be a number, {value, unit} or a text");
            }
            if (iv.number) iv.text = Json(*iv.number).dump();
            b.inputs[k] = iv;
        }
        const Json& events = top.raw("events");
        if (!events.is_array()) top.fail("events", "must be a list");
        for (const Json& e : events) {
            JsonFields f(e, origin, "events[]");
            b.profile.events.push_back({f.string("event", ""), f.raw("depth_mm").get<double>()});
        }
        JsonFields p = top.sub("profile");
        const auto depth = numbers(p.raw("depth_mm"), p, "depth_mm");
        const auto model = numbers(p.raw("model_N"), p, "model_N");
        const auto rendered = numbers(p.raw("rendered_N"), p, "rendered_N");
        const auto plunger = numbers(p.raw("plunger_N"), p, "plunger_N");
        if (depth.empty() || model.size() != depth.size() || rendered.size() != depth.size() ||
            plunger.size() != depth.size())
            p.fail("", "depth_mm, model_N, rendered_N and plunger_N must be non-empty lists of one length");
        for (std::size_t i = 0; i < depth.size(); ++i)
            b.profile.samples.push_back({depth[i], model[i], rendered[i], plunger[i]});
        // The envelope: all six columns or none (a baseline written before it existed).
        std::vector<double> env[6];
        int present = 0;
        for (int k = 0; k < 6; ++k) {
            if (!p.has(kEnvelopeKeys[k])) continue;
            ++present;
            env[k] = numbers(p.raw(kEnvelopeKeys[k]), p, kEnvelopeKeys[k]);
            if (env[k].size() != depth.size()) p.fail(kEnvelopeKeys[k], "must have one value per depth_mm");
        }
        if (present != 0 && present != 6) p.fail("", "give all six envelope columns (*_min_N, *_max_N) or none");
        for (std::size_t i = 0; present && i < depth.size(); ++i)
            b.profile.envelope.push_back({env[0][i], env[1][i], env[2][i], env[3][i], env[4][i], env[5][i]});
        return b;
    });
}

} // namespace

std::optional<Baseline> readBaseline(const std::filesystem::path& file)
{
    std::error_code ec;
    if (!std::filesystem::exists(file, ec)) return std::nullopt;
    // A truncated file is not valid JSON: parse() names the file.
    return baselineFromJson(JsonFields::readFile(file, "baseline"), file.string());
}

Baseline parseBaseline(const std::string& text, const std::string& origin)
{
    return baselineFromJson(JsonFields::parse(text, origin), origin);
}

std::vector<std::string> inputDifferences(const Inputs& before, const Inputs& now)
{
    std::vector<std::string> out;
    const auto show = [](const InputValue& v) { return v.text + (v.unit.empty() ? "" : " " + v.unit); };
    for (const auto& [k, v] : before) {
        auto it = now.find(k);
        if (it == now.end())
            out.push_back(k + " " + show(v) + " → (absent)");
        else if (!(it->second == v))
            out.push_back(k + " " + v.text + " → " + show(it->second));
    }
    for (const auto& [k, v] : now) {
        if (!before.count(k)) out.push_back(k + " (absent) → " + show(v));
    }
    return out;
}

CaseReport compareCase(const Case& c, const CaseRun& run, const std::optional<Baseline>& baseline)
{
    CaseReport r;
    r.name = c.name;
    r.seconds = run.elapsedS;
    r.hasBaseline = baseline.has_value();
    r.digest = run.profile.digest;
    const Tolerance& tol = c.tolerance;
    const auto note = [&](double depth, double delta, double allowed, const std::string& against) {
        if (!r.first || depth < r.first->depthMm)
            r.first = Exceedance{depth, delta, allowed, against, tissueAt(run.layers, depth)};
    };
    const std::vector<Sample>& now = run.profile.samples;
    r.reference = baseline ? "baseline" : "no baseline";

    if (baseline) {
        r.identical = !baseline->profile.digest.empty() && baseline->profile.digest == run.profile.digest;
        r.inputDiffs = inputDifferences(baseline->inputs, run.inputs);
        const bool sameGrid = baseline->profile.samples.size() == now.size();
        for (std::size_t i = 0; i < now.size(); ++i) {
            const Sample ref =
                sameGrid ? baseline->profile.samples[i] : sampleAt(baseline->profile.samples, now[i].depthMm);
            // Model, rendered and plunger force, each within its own tolerance.
            const std::pair<double, double> pairs[3] = {
                {now[i].modelN, ref.modelN}, {now[i].renderedN, ref.renderedN}, {now[i].plungerN, ref.plungerN}};
            for (const auto& [is, was] : pairs) {
                const double d = std::abs(is - was), allowed = tol.absN + tol.rel * std::abs(was);
                if (d > r.maxDeltaN) r.maxDeltaN = d, r.maxDeltaDepthMm = now[i].depthMm;
                if (d > allowed) note(now[i].depthMm, d, allowed, "baseline");
            }
        }
        // Between the samples: the extremes of the ticks each sample stands for.
        const auto& envWas = baseline->profile.envelope;
        const auto& envIs = run.profile.envelope;
        if (sameGrid && envWas.size() == now.size() && envIs.size() == now.size()) {
            for (std::size_t i = 0; i < now.size(); ++i) {
                const Envelope& a = envWas[i];
                const Envelope& b = envIs[i];
                const std::pair<double, double> pairs[6] = {{b.modelMin, a.modelMin}, {b.modelMax, a.modelMax},
                    {b.renderedMin, a.renderedMin}, {b.renderedMax, a.renderedMax}, {b.plungerMin, a.plungerMin},
                    {b.plungerMax, a.plungerMax}};
                const double from = i > 0 ? now[i - 1].depthMm : now[i].depthMm;
                for (const auto& [is, was] : pairs) {
                    const double d = std::abs(is - was), allowed = tol.absN + tol.rel * std::abs(was);
                    if (d > r.maxDeltaN) r.maxDeltaN = d, r.maxDeltaDepthMm = now[i].depthMm;
                    if (d > allowed)
                        note(from, d, allowed,
                            "baseline (a tick between " + fixed(from, 2) + " and " + fixed(now[i].depthMm, 2) + " mm)");
                }
            }
        }
        // Events: the count of each kind exactly, and the depth of each.
        std::map<std::string, std::vector<double>> was, is;
        for (const EventRecord& e : baseline->profile.events) was[e.event].push_back(e.depthMm);
        for (const EventRecord& e : run.profile.events) is[e.event].push_back(e.depthMm);
        std::map<std::string, bool> kinds;
        for (const auto& [k, v] : was) kinds[k] = true;
        for (const auto& [k, v] : is) kinds[k] = true;
        for (const auto& [kind, unused] : kinds) {
            const auto& a = was[kind];
            const auto& b = is[kind];
            if (tol.eventCounts && a.size() != b.size())
                r.eventDiffs.push_back(kind + " count " + std::to_string(a.size()) + " → " + std::to_string(b.size()));
            for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
                if (std::abs(a[i] - b[i]) > tol.eventDepthMm) {
                    r.eventDiffs.push_back(kind + " #" + std::to_string(i + 1) + " depth " + fixed(a[i], 3) + " → " +
                        fixed(b[i], 3) + " mm");
                    note(std::min(a[i], b[i]), 0.0, 0.0, "baseline (" + kind + " moved)");
                }
            }
        }
        // Where the insertion ends is part of what the trainee feels (a moved
        // target landmark changes nothing else): compared like an event.
        if (!baseline->profile.samples.empty() && !now.empty()) {
            const double a = baseline->profile.samples.back().depthMm, b = now.back().depthMm;
            if (std::abs(a - b) > tol.eventDepthMm) {
                r.eventDiffs.push_back("insertion ends at " + fixed(a, 3) + " → " + fixed(b, 3) + " mm");
                note(std::min(a, b), 0.0, 0.0, "baseline (the insertion's end moved)");
            }
        }
        const auto peak = [&](const char* what, double a, double b) {
            if (std::abs(a - b) > tol.peakN)
                r.peakDiffs.push_back(std::string(what) + " " + fixed(a, 4) + " → " + fixed(b, 4) + " N");
        };
        peak("peak model force", baseline->profile.peakModelN, run.profile.peakModelN);
        peak("peak rendered force", baseline->profile.peakRenderedN, run.profile.peakRenderedN);
    }

    // The closed form, with the values the baseline recorded (clarifications: an
    // edited tissue value fails here too, not only against the stored profile).
    static const Inputs kNone;
    const ClosedFormCheck cf = closedForm(c, baseline ? baseline->inputs : kNone, run.inputs, now);
    r.closedForm = cf.line();
    if (cf) {
        r.reference = std::string(baseline ? "baseline + " : "") + cf->rule;
        double worst = 0;
        for (std::size_t i = 0; i < now.size(); ++i) {
            if (!std::isfinite(cf->toleranceN[i])) continue; // a sample the rule does not compare
            const double d = std::abs(now[i].modelN - cf->modelN[i]);
            worst = std::max(worst, d);
            if (!baseline && d > r.maxDeltaN) r.maxDeltaN = d, r.maxDeltaDepthMm = now[i].depthMm;
            if (d > cf->toleranceN[i]) note(now[i].depthMm, d, cf->toleranceN[i], cf->rule);
        }
        r.closedFormMaxDeltaN = worst;
        // The events the rule places (R4's pops), in order, within the rule's slack.
        std::map<std::string, std::vector<double>> want, got;
        for (const ExpectedEvent& e : cf->events) want[e.event].push_back(e.depthMm);
        for (const EventRecord& e : run.profile.events) {
            if (want.count(e.event) && e.depthMm < cf->eventsUpToMm) got[e.event].push_back(e.depthMm);
        }
        for (const auto& [kind, depths] : want) {
            const auto& is = got[kind];
            if (is.size() != depths.size()) {
                r.eventDiffs.push_back(kind + " count " + std::to_string(depths.size()) + " (" + cf->rule + ") → " +
                    std::to_string(is.size()));
                note(std::min(depths.empty() ? 1e300 : depths.front(), is.empty() ? 1e300 : is.front()), 0.0, 0.0,
                    cf->rule + " (" + kind + " count)");
            }
        }
        std::map<std::string, std::size_t> seen;
        for (const ExpectedEvent& e : cf->events) {
            const std::size_t k = seen[e.event]++;
            const auto& is = got[e.event];
            if (k >= is.size() || std::abs(is[k] - e.depthMm) <= e.toleranceMm) continue;
            r.eventDiffs.push_back(e.event + " #" + std::to_string(k + 1) + " depth " + fixed(e.depthMm, 3) + " (" +
                cf->rule + ") → " + fixed(is[k], 3) + " mm");
            note(std::min(e.depthMm, is[k]), 0.0, 0.0, cf->rule + " (" + e.event + " moved)");
        }
    }
    // A deflection measured in the literature (physics.md §9.2): the deviation is
    // stated whether it passes or not.
    r.tipDeviationMm = run.tipDeviationMm;
    if (c.measured) {
        const Measured& m = *c.measured;
        const double got = run.tipDeviationMm.value_or(0.0);
        r.measuredPass = run.tipDeviationMm && std::abs(got - m.tipDeviationMm) <= m.toleranceMm;
        r.measured = fixed(m.tipDeviationMm, 2) + " mm measured (" + m.source + "), model " +
            (run.tipDeviationMm ? fixed(got, 2) + " mm" : std::string("no bending needle")) +
            (m.tipDeviationMm > 0.0 && run.tipDeviationMm ? ", " + std::string(got >= m.tipDeviationMm ? "+" : "") +
                        fixed(100.0 * (got - m.tipDeviationMm) / m.tipDeviationMm, 0) + " %"
                                                          : std::string()) +
            ", tolerance " + fixed(m.toleranceMm, 2) + " mm";
        r.reference += " + measured tip deviation";
    }
    r.pass = baseline && !r.first && r.eventDiffs.empty() && r.peakDiffs.empty() && r.measuredPass;
    return r;
}

} // namespace voxhap::regress
