// SPDX-License-Identifier: Apache-2.0
/// @file CmdDemo.cpp
/// @brief `voxhap demo`: the end-to-end job on a built-in phantom. For now:
/// generate the lumbar epidural phantom, describe it, and run the [S19]
/// average-patient epidural insertion through it (planning and rendering join
/// when they exist).

#include "tools/Cli.h"
#include "tools/InfoReport.h"
#include "tools/SimulationOutputs.h"

#include "haptic/Insertion.h"
#include "haptic/Scene.h"

#include "volume/Phantoms.h"
#include "volume/VdbFile.h"

#include <filesystem>
#include <iostream>
#include <memory>

namespace voxhap::tools {

namespace {

struct DemoOptions {
    CommonOptions common;
    std::string outDir = "voxhap-demo";
};

int run(const DemoOptions& o)
{
    const volume::TissueTable& table = tissueTable(o.common);
    std::filesystem::create_directories(o.outDir);
    const std::string file = (std::filesystem::path(o.outDir) / "lumbar.vdb").string();
    auto v = std::make_shared<const volume::Volume>(
        volume::makePhantom(volume::lumbarModel({}, table), volume::GridSpec{}, table));
    volume::saveVdb(*v, file);
    const auto info = volume::describe(*v, table);

    // The average patient of [S19]: a 2 mm/s insertion from 5 mm above the skin into the epidural space.
    const haptic::Scene scene = haptic::loadScene("senac-average");
    const haptic::SceneInstance inst(scene, v, table);
    auto model = inst.makeModel();
    const double depth = (inst.target() - inst.entry()).norm();
    const haptic::InsertionResult r = haptic::runInsertion(
        *model, haptic::InsertionScript::constantSpeed(-scene.approachMm, depth, scene.speedMmPerS), scene.rateHz);
    const SimulationFiles sim = writeSimulation(r, inst, (std::filesystem::path(o.outDir) / "insertion").string(), true);

    if (o.common.json) {
        std::cout << nlohmann::json{{"volume", infoJson(info, file)}, {"insertion", sim.summary}}.dump(2) << '\n';
        return 0;
    }
    std::cout << "voxhap demo: lumbar epidural phantom (average patient, 0.5 mm voxels)\n\n";
    printInfo(std::cout, info, file);
    std::cout << "\nepidural insertion, scene " << scene.name << " (" << scene.speedMmPerS << " mm/s to the epidural space):\n"
              << haptic::insertionSummaryText(r, inst.layers());
    std::cout << "\noutputs:\n  " << file << "  (open with `voxhap info`, or in any OpenVDB viewer)\n";
    printOutputs(std::cout, sim);
    if (!sim.plotted) std::cerr << "voxhap demo: no plot: " << sim.plotWhy << '\n';
    return 0;
}

} // namespace

Action registerDemo(CLI::App& app)
{
    auto o = std::make_shared<DemoOptions>();
    CLI::App* cmd = app.add_subcommand("demo", "Run the main job on a built-in phantom and say where the outputs are");
    cmd->add_option("--out,-o", o->outDir, "Output directory (default voxhap-demo)");
    addCommonOptions(*cmd, o->common);
    return [o] { return run(*o); };
}

} // namespace voxhap::tools
