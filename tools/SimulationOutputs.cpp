// SPDX-License-Identifier: Apache-2.0
/// @file SimulationOutputs.cpp
#include "tools/SimulationOutputs.h"

#include "core/AtomicFile.h"
#include "render/plots/ForcePlot.h"

#include <cmath>
#include <filesystem>
#include <fstream>

namespace voxhap::tools {

namespace {

namespace fs = std::filesystem;

nlohmann::json summaryJson(
    const haptic::InsertionResult& r, const haptic::Scene& scene, const std::string& csv, const std::string& png)
{
    const haptic::InsertionSummary& s = r.summary;
    const auto depth = [](double d) { return std::isfinite(d) ? nlohmann::json(d) : nlohmann::json(nullptr); };
    nlohmann::json events = nlohmann::json::array();
    for (const haptic::Event& e : r.events) {
        events.push_back(
            {{"event", haptic::eventName(e.type)}, {"t_s", e.timeS}, {"depth_mm", e.depthMm}, {"layer", e.layer}});
    }
    const haptic::ProcedureOutcome& o = r.outcome;
    const auto opt = [](const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); };
    nlohmann::json j = {{"scene", scene.name}, {"success", o.success},
        {"success_rule", haptic::successRuleName(o.rule)}, {"success_reason", o.reason},
        {"target_distance_mm", opt(o.targetDistanceMm)}, {"force_limited", s.forceLimits},
        {"force_limited_first_mm", depth(s.firstLimitMm)}, {"force_limited_ticks", s.limitedTicks},
        {"force_limited_max_cut_N", s.maxLimitedN}, {"skin_puncture_mm", depth(s.skinEntryMm)}, {"pops", s.pops},
        {"loss_of_resistance_mm", depth(s.lorMm)}, {"dura_puncture_mm", depth(s.duraMm)},
        {"bone_contact_mm", depth(s.boneMm)}, {"critical_breach_mm", depth(s.breachMm)},
        {"peak_model_force_N", s.peakModelN}, {"peak_rendered_force_N", s.peakRenderedN},
        {"peak_plunger_force_N", s.peakPlungerN}, {"faults", s.faults}, {"final_depth_mm", s.finalDepthMm},
        {"duration_s", s.durationS}, {"events", events}, {"csv", csv}, {"png", png}};
    if (s.guidance) j["guidance"] = {{"peak_force_N", s.peakGuidanceN}, {"max_offset_mm", s.maxOffsetMm}};
    if (s.bending) {
        nlohmann::json shaft = nlohmann::json::array();
        for (const Vec3d& p : r.bentShaft) shaft.push_back({p.x(), p.y(), p.z()});
        j["bending"] = {{"tip_deviation_mm", s.tipDeviationMm}, {"max_tip_deviation_mm", s.maxTipDeviationMm},
            {"shaft", std::move(shaft)}};
    }
    return j;
}

} // namespace

SimulationFiles writeSimulation(
    const haptic::InsertionResult& r, const haptic::SceneInstance& inst, const std::string& outDir, bool plot)
{
    const haptic::Scene& scene = inst.scene();
    fs::create_directories(outDir);
    SimulationFiles f;
    f.csv = (fs::path(outDir) / "insertion.csv").string();
    f.json = (fs::path(outDir) / "summary.json").string();
    const std::string png = (fs::path(outDir) / "force-depth.png").string();
    // The three outputs replace an earlier run's together (OutputSet): never a new
    // insertion.csv beside a stale summary.json or plot. The plot is drawn first, under
    // the name the set puts in place, since gnuplot may be missing; without it an
    // earlier plot is removed, not left beside the new table.
    OutputSet out;
    out.add(f.csv, [&](const fs::path& tmp) { haptic::writeInsertionCsv(r, inst.layers(), tmp); });
    const fs::path pngTemporary = temporaryPathFor(png);
    f.plotted = plot &&
        render::plotForceDepth(render::forceTrace(r, inst.layers(), scene.name + ": " + scene.description),
            pngTemporary.string(), f.plotWhy);
    if (f.plotted) {
        f.png = png;
        out.add(png, [](const fs::path&) {}); // already written at its temporary path
    } else {
        std::error_code ignored;
        fs::remove(pngTemporary, ignored);
        out.remove(png);
    }
    f.summary = summaryJson(r, scene, f.csv, f.png);
    out.addStream(f.json, [&](std::ostream& o) { o << f.summary.dump(2) << '\n'; });
    try {
        out.commit();
    } catch (...) {
        std::error_code ignored;
        fs::remove(pngTemporary, ignored);
        throw;
    }
    return f;
}

void printOutputs(std::ostream& os, const SimulationFiles& f)
{
    os << "  " << f.csv << "  (one row per servo tick)\n  " << f.json << "  (events and peaks)\n";
    if (f.plotted) os << "  " << f.png << "  (force against depth, layers and events)\n";
}

} // namespace voxhap::tools
