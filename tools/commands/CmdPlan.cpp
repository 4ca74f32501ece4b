// SPDX-License-Identifier: Apache-2.0
/// @file CmdPlan.cpp
/// @brief `voxhap plan <volume> --target x,y,z [--entry x,y,z | --entries paths.mrk.json] [--top N] [--out dir]`:
/// analyse a given path, or search candidate entries, and write the report,
/// 3D Slicer markups, slice views with the paths and the predicted force–depth plot.
/// The outputs are render/outputs/PlanOutputs.h's, which `voxhap demo` writes too.

#include "core/Format.h"
#include "tools/Cli.h"
#include "tools/LoadOptions.h"

#include "core/Errors.h"
#include "planning/Deflection.h"
#include "planning/Markups.h"
#include "planning/Report.h"
#include "planning/Search.h"
#include "render/outputs/PlanOutputs.h"
#include "render/volume3d/Display.h"
#include "segmentation/DistanceField.h"
#include "segmentation/Segmentation.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

namespace voxhap::tools {

namespace fs = std::filesystem;

namespace {

struct PlanCliOptions {
    CommonOptions common;
    ReaderOptions reader;
    std::string in, target, entry, entries, out = "voxhap-plan", scene = "kyung", reference = "0,1,0", entryBox;
    int top = 5;
    double speed = 0, maxAngle = 45, maxLength = 0, minClearance = 5, step = 2, margin = 20;
    bool allowBone = false, noViews = false;
};

planning::Box parseBox(const std::string& text)
{
    std::vector<double> v;
    std::stringstream in(text);
    for (std::string item; std::getline(in, item, ',');) {
        try {
            std::size_t used = 0;
            v.push_back(std::stod(item, &used));
            if (used != item.size()) throw std::invalid_argument(item);
        } catch (const std::exception&) {
            throw UsageError("--entry-box '" + text + "': expected six numbers x0,y0,z0,x1,y1,z1 [mm]");
        }
    }
    if (v.size() != 6) throw UsageError("--entry-box '" + text + "': expected six numbers x0,y0,z0,x1,y1,z1 [mm]");
    planning::Box b{Vec3d(v[0], v[1], v[2]), Vec3d(v[3], v[4], v[5])};
    if ((b.min.array() > b.max.array()).any())
        throw UsageError("--entry-box: each minimum must not exceed its maximum");
    return b;
}

/// Labels and distance fields: what the volume lacks is computed (segment()).
void ensureSegmented(volume::Volume& v, const volume::TissueTable& table, bool progress, std::uint64_t capBytes)
{
    bool anyField = false;
    for (const auto& t : table.tissues())
        anyField = anyField || (t.critical && v.derived(segmentation::distanceFieldName(t.name)));
    if (v.has(volume::Channel::Label) && anyField) return;
    segmentation::SegmentOptions so;
    so.automatic = !v.has(volume::Channel::Label); // keep given labels; only add their distance fields
    if (progress) so.progress = [](double, std::string_view step) { std::cerr << "plan: " << step << "...\n"; };
    so.memoryCapBytes = capBytes;
    segmentation::segment(v, table, so);
}

void printPath(std::ostream& os, const planning::TrajectoryReport& r, int rank)
{
    os << "#" << rank << "  risk " << fixed(r.risk.total, 2) << "  entry (" << fixed(r.entry.x()) << ", "
       << fixed(r.entry.y()) << ", " << fixed(r.entry.z()) << ")  length " << fixed(r.lengthMm) << " mm  clearance "
       << (std::isfinite(r.minClearanceMm) ? fixed(r.minClearanceMm) + " mm" : std::string("n/a"));
    if (!r.nearestStructure.empty()) os << " (" << r.nearestStructure << ")";
    os << "  peak " << fixed(r.peakForceN, 2) << " N\n     ";
    for (std::size_t i = 0; i < r.segments.size(); ++i) {
        os << (i ? " > " : "") << r.segments[i].tissue << " " << fixed(r.segments[i].lengthMm());
    }
    os << "\n";
    if (const auto& d = r.deflection) { // physics.md §9.6
        const planning::BevelChoice& b = d->best;
        os << "     bent needle: tip " << fixed(b.tipToTargetMm, 1) << " mm from the target ("
           << fixed(b.tipDeviationMm, 1) << " mm off the line) with the bevel at " << fixed(b.orientationDeg, 0)
           << " deg" << (std::isfinite(b.turnDepthMm) ? ", turned 180 deg at " + fixed(b.turnDepthMm, 0) + " mm" : "");
        for (const auto& c : d->tried) {
            if (!std::isfinite(c.turnDepthMm))
                os << "; " << fixed(c.tipDeviationMm, 1) << " mm at " << fixed(c.orientationDeg, 0) << " deg unturned";
        }
        os << "\n";
    }
    for (const auto& w : r.warnings) os << "     warning: " << w.message << "\n";
}

} // namespace

void printPlanFiles(std::ostream& os, const render::PlanFiles& f)
{
    os << "  " << f.report << "  (report: segments, clearances, force profile, warnings, risk)\n";
    os << "  " << f.markups << "  (3D Slicer markups: one Line per path, LPS mm)\n";
    if (!f.views.empty()) {
        os << "  " << f.views << "  (axial, sagittal, coronal slices through the target"
           << (f.why3d.empty() ? " and a 3D view" : "") << ", paths drawn)\n";
        if (!f.why3d.empty()) os << "     no 3D view: " << f.why3d << "\n";
    }
    if (!f.plot.empty()) os << "  " << f.plot << "  (predicted force against depth, path 1)\n";
}

namespace {

int run(const PlanCliOptions& o)
{
    // Cheap checks first: bad values fail before the volume loads.
    // The Lines of a markups file carry their own targets: --target is for the others.
    if (o.entries.empty() && o.target.empty())
        throw UsageError("--target is required (unless --entries gives the paths)");
    if (!o.entries.empty() && !o.target.empty()) {
        throw UsageError("--target and --entries exclude each other: the markups' Lines give the targets");
    }
    std::optional<Vec3d> entry;
    if (!o.entry.empty()) entry = parseVec3(o.entry, "--entry");
    if (entry && !o.entries.empty()) throw UsageError("--entry and --entries exclude each other");
    std::vector<planning::MarkupLine> given;
    if (!o.entries.empty()) given = planning::loadMarkups(o.entries);
    if (!o.entries.empty() && given.empty()) throw IoError(o.entries + ": no Line markup with two control points");
    const Vec3d target = given.empty() ? parseVec3(o.target, "--target") : given.front().target;
    planning::SearchConstraints k;
    k.reference = parseVec3(o.reference, "--reference");
    if (!(k.reference.norm() > 0)) throw UsageError("--reference must not be zero");
    k.maxAngleDeg = o.maxAngle;
    k.maxLengthMm = o.maxLength;
    k.allowBoneObstacles = o.allowBone;
    if (!o.entryBox.empty()) k.entryBox = parseBox(o.entryBox);
    const haptic::Scene scene = haptic::loadScene(o.scene);
    const volume::TissueTable& table = tissueTable(o.common);
    const bool terminal = stderrIsTerminal() && !o.common.json;
    // The views' X display, started now and waited for at the views: Xvfb comes
    // up (0.2–0.4 s) while the volume loads and is segmented.
    std::optional<render::DisplayGuard> display;
    if (!o.noViews) display.emplace(10.0, false);

    auto v = std::make_shared<volume::Volume>(loadVolumeWithProgress(o.in, o.reader, terminal));
    {
        const auto b = v->worldBounds();
        if ((target.array() < b[0].array()).any() || (target.array() > b[1].array()).any()) {
            throw UsageError("--target lies outside the volume's bounds");
        }
    }
    const auto capBytes = std::uint64_t(o.reader.memoryCapMb * double(1 << 20));
    ensureSegmented(*v, table, terminal, capBytes);
    planning::checkMemoryCap(*v, capBytes);
    planning::PlanOptions po;
    po.speedMmPerS = o.speed;
    po.minClearanceMm = o.minClearance;
    po.marginMm = o.margin;
    const planning::Planner planner(v, table, scene, po);

    nlohmann::json report = planning::reportHeader(planner, o.in);
    std::vector<planning::TrajectoryReport> paths;
    std::optional<planning::SearchResult> found;
    if (entry) {
        paths.push_back(planner.analyze(*entry, target));
    } else if (!given.empty()) {
        for (const auto& l : given) paths.push_back(planner.analyze(l.entry, l.target));
    } else {
        planning::SearchOptions so;
        so.stepDeg = o.step;
        so.top = o.top;
        found = planning::search(planner, target, k, so);
        paths = found->ranked;
        report["search"] = planning::searchJson(planner, *found, k, so);
        report["pareto"] = nlohmann::json::array();
        for (const auto& p : found->pareto) report["pareto"].push_back(planning::pathJson(p, 0));
    }
    // A bending needle: where its tip will end on each path, per bevel orientation
    // and turn depth (physics.md §9.6); only for the paths reported.
    planning::predictDeflections(planner, paths);
    report["paths"] = nlohmann::json::array();
    for (std::size_t i = 0; i < paths.size(); ++i) report["paths"].push_back(planning::pathJson(paths[i], int(i) + 1));

    const render::PlanFiles files =
        render::writePlanOutputs(planner, paths, report, o.out, !o.noViews, display ? &*display : nullptr);
    if (o.common.json) {
        nlohmann::json j = report;
        j["outputs"] = {{"report", files.report}, {"markups", files.markups}, {"views", files.views},
            {"plot", files.plot}, {"views_3d", !files.views.empty() && files.why3d.empty()},
            {"why_no_3d", files.why3d}};
        std::cout << j.dump(2) << '\n';
    } else {
        std::cout << "plan to (" << fixed(target.x()) << ", " << fixed(target.y()) << ", " << fixed(target.z())
                  << ") in " << o.in << ", scene " << scene.name << ", " << fixed(planner.speedMmPerS(), 0)
                  << " mm/s\n";
        if (found) {
            std::cout << "searched " << found->counts.directions << " directions: " << found->counts.analysed
                      << " analysed, " << found->counts.feasible << " feasible, " << found->pareto.size()
                      << " on the Pareto front, in " << fixed(found->seconds, 3) << " s\n";
        }
        std::cout << "\n";
        for (std::size_t i = 0; i < paths.size(); ++i) printPath(std::cout, paths[i], int(i) + 1);
        if (paths.empty()) std::cout << "no path satisfies the constraints (see the report's rejection counts)\n";
        std::cout << "\noutputs:\n";
        printPlanFiles(std::cout, files);
    }
    if (files.plot.empty() && !paths.empty()) std::cerr << "voxhap plan: no plot: " << files.why << '\n';
    return paths.empty() ? kExitFailure : 0;
}

} // namespace

Action registerPlan(CLI::App& app)
{
    auto o = std::make_shared<PlanCliOptions>();
    CLI::App* cmd = app.add_subcommand("plan",
        "Biopsy path planning: analyse a path (--entry) or search entries to a target; report, Slicer markups, "
        "views and the predicted force-depth plot");
    cmd->add_option("volume", o->in,
           "Volume: DICOM, .nii, .nrrd, .mha or .vdb (segmented if it has no labels and distance fields)")
        ->required();
    cmd->add_option("--target", o->target, "Target x,y,z [mm, LPS] (required unless --entries)");
    cmd->add_option("--entry", o->entry, "Entry x,y,z [mm, LPS]: analyse this path instead of searching");
    cmd->add_option("--entries", o->entries, "Analyse the Line markups of this 3D Slicer .mrk.json");
    cmd->add_option("--top", o->top, "Ranked candidates to keep")->check(CLI::Range(1, 1000))->default_val(5);
    cmd->add_option("--out,-o", o->out, "Output directory (default voxhap-plan)");
    cmd->add_option("--scene", o->scene, "Scene whose force model, needle and device are used (default kyung)");
    cmd->add_option("--speed", o->speed, "Insertion speed of the force prediction [mm/s]; default the scene's")
        ->check(CLI::PositiveNumber);
    cmd->add_option(
        "--reference", o->reference, "Search: outward reference direction x,y,z (default 0,1,0: posterior)");
    cmd->add_option("--max-angle", o->maxAngle, "Search: largest angle from the reference [deg]")
        ->check(CLI::Range(0.0, 180.0))
        ->default_val(45);
    cmd->add_option("--max-length", o->maxLength, "Search: longest path [mm]; default the needle's length")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--min-clearance", o->minClearance, "Smallest clearance to a critical structure [mm]")
        ->check(CLI::NonNegativeNumber)
        ->default_val(5);
    cmd->add_option("--margin", o->margin, "Risk margin: structures nearer than this raise the risk [mm]")
        ->check(CLI::PositiveNumber)
        ->default_val(20);
    cmd->add_option("--step", o->step, "Search: direction grid spacing [deg]")
        ->check(CLI::Range(0.1, 45.0))
        ->default_val(2);
    cmd->add_option("--entry-box", o->entryBox, "Search: entries only in the box x0,y0,z0,x1,y1,z1 [mm, LPS]");
    cmd->add_flag("--allow-bone", o->allowBone, "Search: accept paths that cross bone before the target's own");
    cmd->add_flag("--no-views", o->noViews, "Do not render the slice views");
    addReaderOptions(*cmd, o->reader);
    addCommonOptions(*cmd, o->common);
    return [o] { return run(*o); };
}

} // namespace voxhap::tools
