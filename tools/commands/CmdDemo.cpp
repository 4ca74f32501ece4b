// SPDX-License-Identifier: Apache-2.0
/// @file CmdDemo.cpp
/// @brief `voxhap demo`: the main job end to end on the built-in torso phantom —
/// phantom → CT segmentation (labels and distance fields) → path search to the
/// vertebral lesion → simulated insertion along the best path → views with the
/// paths and the force–depth plots — printing a short summary and every output.

#include "tools/Cli.h"
#include "tools/SimulationOutputs.h"

#include "core/Errors.h"
#include "haptic/scene/Scene.h"
#include "haptic/scene/ScriptedInsertion.h"
#include "phantoms/Phantoms.h"
#include "planning/Report.h"
#include "planning/Search.h"
#include "render/outputs/PlanOutputs.h"
#include "segmentation/Segmentation.h"
#include "volume/Grids.h"
#include "volume/io/VdbFile.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>

namespace voxhap::tools {

namespace {

namespace fs = std::filesystem;

/// Slice spacing of the demo's CT [mm]: that of the real series in ../shared/data,
/// and what the spinal-canal rule of the CT segmentation is tuned on.
constexpr double kSliceMm = 3.0;

struct DemoOptions {
    CommonOptions common;
    std::string outDir = "voxhap-demo";
    double spacingMm = 1.0;
};

double since(std::chrono::steady_clock::time_point t)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

int run(const DemoOptions& o)
{
    const volume::TissueTable& table = tissueTable(o.common);
    const bool terminal = stderrIsTerminal() && !o.common.json;
    const auto say = [&](const std::string& step) {
        if (terminal) std::cerr << "demo: " << step << "...\n";
    };
    fs::create_directories(o.outDir);
    const auto start = std::chrono::steady_clock::now();

    // 1. The spine-biopsy torso (physics.md §1.1) as a CT: its HU grid is what segmentation reads.
    say("torso phantom");
    volume::GridSpec grid;
    grid.spacing = Vec3d(o.spacingMm, o.spacingMm, kSliceMm); // a CT series: fine pixels, thicker slices
    const volume::PhantomModel model = volume::torsoModel({}, table);
    auto v = std::make_shared<volume::Volume>(volume::makePhantom(model, grid, table));
    const Vec3d lesion = *volume::phantomLandmark(*v, "lesion");

    // The spinal canal as an imported label map (a 3D Slicer segmentation would play
    // this part on a scan): CT segmentation finds the canal as the hole of a closed
    // bony ring, and the phantom's arch does not close on its vertebral body
    // (tests/segmentation/TestCtSegmentation.cpp), yet the planner must see the cord.
    // The whole canal (CSF and cord) is imported as cord: the margin a planner keeps.
    const int cord = table.at("spinal_cord").id, csf = table.at("csf").id;
    volume::Volume canal(v->transformPtr()->copy(), v->indexBox());
    {
        auto labels = volume::LabelGrid::create(0);
        labels->setTransform(v->transformPtr()->copy());
        auto out = labels->getAccessor();
        const auto truth = volume::labelGrid(*v);
        for (auto it = truth->cbeginValueOn(); it; ++it) {
            if (*it == cord || *it == csf) out.setValue(it.getCoord(), cord);
        }
        canal.setGrid(volume::Channel::Label, labels);
    }
    v->removeGrid(volume::Channel::Label); // everything else is found again by segmentation, as on a scan

    // 2. Segmentation: labels and the critical structures' distance fields.
    segmentation::SegmentOptions so;
    so.progress = [&say](double, std::string_view step) { say(std::string(step)); };
    segmentation::ImportedLabels imported;
    imported.labels = &canal;
    imported.mapping.tissueOf = {{cord, cord}};
    imported.mapping.origin = "the torso phantom's spinal canal";
    imported.file = "builtin:torso spinal canal";
    so.imported = imported;
    const segmentation::SegmentReport seg = segmentation::segment(*v, table, so);
    const std::string vdb = (fs::path(o.outDir) / "torso-segmented.vdb").string();
    volume::saveVdb(*v, vdb);

    // 3. Search entries to the lesion from the back (the patient lies prone).
    say("path search");
    const haptic::Scene scene = haptic::loadScene("kyung");
    const planning::Planner planner(v, table, scene);
    planning::SearchConstraints k;
    k.reference = Vec3d(0, 1, 0);
    k.maxAngleDeg = 60.0;
    planning::SearchOptions sopt;
    sopt.stepDeg = 2.0;
    sopt.top = 3;
    const planning::SearchResult found = planning::search(planner, lesion, k, sopt);
    if (found.ranked.empty()) throw Error("demo: no safe path to the lesion was found");
    const planning::TrajectoryReport& best = found.ranked.front();

    // 4. Plan outputs: report, markups, views with the paths, predicted force–depth plot.
    say("plan outputs");
    nlohmann::json report = planning::reportHeader(planner, "builtin:torso");
    report["paths"] = nlohmann::json::array();
    for (std::size_t i = 0; i < found.ranked.size(); ++i)
        report["paths"].push_back(planning::pathJson(found.ranked[i], int(i) + 1));
    report["pareto"] = nlohmann::json::array();
    for (const auto& p : found.pareto) report["pareto"].push_back(planning::pathJson(p, 0));
    report["search"] = planning::searchJson(planner, found, k, sopt);
    const render::PlanFiles plan =
        render::writePlanOutputs(planner, found.ranked, report, (fs::path(o.outDir) / "plan").string(), true);

    // 5. The simulated insertion along the best path, at the scene's speed, to the
    //    first bone contact (the model renders bone as contact: §1.3).
    say("simulated insertion");
    const haptic::SceneInstance inst(scene, v, table, best.entry, best.target);
    auto forceModel = inst.makeModel();
    // 1 mm past the predicted contact: far enough that the tip reaches the bone's
    // surface whatever the tick spacing, within the contact's stiffness range.
    constexpr double kPastContactMm = 1.0;
    const double depth = std::isfinite(best.contactMm) ? best.contactMm + kPastContactMm : best.lengthMm;
    const haptic::InsertionResult r = haptic::runInsertion(*forceModel,
        haptic::InsertionScript::constantSpeed(-scene.approachMm, depth, scene.speedMmPerS), scene.rateHz,
        scene.success, inst.target());
    const SimulationFiles sim = writeSimulation(r, inst, (fs::path(o.outDir) / "insertion").string(), true);
    const double seconds = since(start);

    if (o.common.json) {
        std::cout << nlohmann::json{{"volume", vdb}, {"segmentation_seconds", seg.seconds}, {"plan", report},
                         {"plan_files",
                             {{"report", plan.report}, {"markups", plan.markups}, {"views", plan.views},
                                 {"plot", plan.plot}}},
                         {"insertion", sim.summary}, {"seconds", seconds}}
                         .dump(2)
                  << '\n';
        return 0;
    }
    std::cout << std::fixed << std::setprecision(1);
    std::cout << "voxhap demo: spine biopsy on the torso phantom (" << o.spacingMm << " x " << o.spacingMm << " x "
              << kSliceMm << " mm voxels)\n\n"
              << "segmented " << seg.labels.size() << " labels in " << seg.seconds << " s; distance fields:";
    for (const auto& d : seg.distanceFields) std::cout << ' ' << d;
    if (seg.importedVoxels)
        std::cout << " (spinal canal imported from the phantom: " << seg.importedVoxels << " voxels)";
    std::cout << "\nsearched " << found.counts.directions << " directions to the lesion at (" << lesion.x() << ", "
              << lesion.y() << ", " << lesion.z() << "): " << found.counts.analysed << " analysed, "
              << found.counts.feasible << " safe, in " << std::setprecision(3) << found.seconds << " s\n"
              << std::setprecision(1) << "best path: " << best.lengthMm << " mm, clearance " << best.minClearanceMm
              << " mm to the " << best.nearestStructure << ", predicted peak " << std::setprecision(2)
              << best.peakForceN << " N, risk " << best.risk.total << "\n           ";
    for (std::size_t i = 0; i < best.segments.size(); ++i) std::cout << (i ? " > " : "") << best.segments[i].tissue;
    std::cout << "\n\nsimulated insertion, scene " << scene.name << " (" << std::setprecision(0) << scene.speedMmPerS
              << " mm/s along the best path):\n"
              << haptic::insertionSummaryText(r, inst.layers());
    std::cout << "\noutputs:\n  " << vdb << "  (segmented volume with distance fields: `voxhap info`, `voxhap plan`)\n";
    printPlanFiles(std::cout, plan);
    printOutputs(std::cout, sim);
    std::cout << std::setprecision(1) << "\ndone in " << seconds << " s\n";
    if (!sim.plotted) std::cerr << "voxhap demo: no plot: " << sim.plotWhy << '\n';
    return 0;
}

} // namespace

Action registerDemo(CLI::App& app)
{
    auto o = std::make_shared<DemoOptions>();
    CLI::App* cmd = app.add_subcommand("demo",
        "Spine biopsy end to end on the torso phantom: segment, plan, simulate, render; say where the outputs are");
    cmd->add_option("--out,-o", o->outDir, "Output directory (default voxhap-demo)");
    cmd->add_option("--spacing", o->spacingMm, "Phantom pixel size in-plane [mm] (default 1; slices are 3 mm)")
        ->check(CLI::Range(0.5, 3.0));
    addCommonOptions(*cmd, o->common);
    return [o] { return run(*o); };
}

} // namespace voxhap::tools
