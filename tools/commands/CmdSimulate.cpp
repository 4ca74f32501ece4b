// SPDX-License-Identifier: Apache-2.0
/// @file CmdSimulate.cpp
/// @brief `voxhap simulate`: a constant-speed or scripted insertion through a
/// scene's force model → CSV, force–depth PNG and a summary.

#include "tools/Cli.h"
#include "tools/Guide.h"
#include "tools/SimulationOutputs.h"

#include "core/BoundedRead.h"
#include "core/Errors.h"
#include "haptic/scene/Scene.h"
#include "haptic/scene/ScriptedInsertion.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

namespace voxhap::tools {

namespace {

namespace fs = std::filesystem;

struct SimulateOptions {
    CommonOptions common;
    std::string input; ///< .vdb file or phantom name, optional
    std::string scene;
    std::string entry, target, script, out = "voxhap-simulate";
    double speed = 0, depth = 0, rate = 0;
    bool noPlot = false;
    GuideOptions guide;
};

/// "lumbar", "lumbar:overweight", "torso", or a .vdb file.
haptic::VolumeSource sourceFor(const std::string& input, const haptic::VolumeSource& scene)
{
    haptic::VolumeSource s;
    s.spacingMm = scene.spacingMm;
    const auto colon = input.find(':');
    const std::string kind = input.substr(0, colon);
    if (kind == "lumbar" || kind == "torso") {
        s.phantom = kind;
        if (colon != std::string::npos) s.preset = input.substr(colon + 1);
        return s;
    }
    if (!fs::exists(input)) throw IoError(input + ": no such volume (or phantom: lumbar[:preset], torso)");
    requireRegularFile(input, "volume", /*allowDirectory=*/true); // not a FIFO or a device
    s.file = input;
    return s;
}

int run(const SimulateOptions& o, const CLI::App& cmd)
{
    const volume::TissueTable& table = tissueTable(o.common);
    const std::optional<haptic::GuideLine> guide = guideLine(o.guide, cmd); // a bad plan file fails first
    const haptic::Scene scene = loadSceneSayingDefaults(o.scene);
    std::optional<Vec3d> entry, target;
    if (!o.entry.empty()) entry = parseVec3(o.entry, "--entry");
    if (!o.target.empty()) target = parseVec3(o.target, "--target");
    if (cmd.count("--script") && (cmd.count("--speed") || cmd.count("--depth"))) {
        throw UsageError("--script gives the motion: --speed and --depth do not apply");
    }
    std::shared_ptr<const volume::Volume> vol;
    if (!o.input.empty()) vol = haptic::makeSourceVolume(sourceFor(o.input, scene.volume), table);
    const haptic::SceneInstance inst(scene, vol, table, entry, target);

    const double speed = cmd.count("--speed") ? o.speed : scene.speedMmPerS;
    const double rate = cmd.count("--rate") ? o.rate : scene.rateHz;
    const double pathLength = (inst.target() - inst.entry()).norm();
    const double depth = cmd.count("--depth") ? o.depth : scene.depthMm.value_or(pathLength);
    const haptic::InsertionScript script = o.script.empty()
        ? haptic::InsertionScript::constantSpeed(-scene.approachMm, depth, speed)
        : haptic::InsertionScript::load(o.script);
    if (script.duration() * rate > 5e7) throw UsageError("--rate and the insertion give more than 5e7 ticks");

    auto model = inst.makeModel(guide);
    const haptic::InsertionResult r = haptic::runInsertion(*model, script, rate, scene.success, inst.target());

    const SimulationFiles files = writeSimulation(r, inst, o.out, !o.noPlot);
    if (o.common.json) {
        std::cout << files.summary.dump(2) << '\n';
    } else {
        std::cout << "voxhap simulate: " << scene.name << " (" << haptic::layerModelName(scene.recipe.model) << ", "
                  << (scene.fixedTable ? "the paper's layer table" : "layers from the labels on the path") << ")\n"
                  << "  path " << inst.entry().transpose() << " -> " << inst.target().transpose() << " mm, "
                  << (o.script.empty() ? std::to_string(speed) + " mm/s" : "scripted") << ", " << rate << " Hz, device "
                  << scene.device.name << "\n";
        if (model->guidance()) {
            std::cout << "  guidance toward "
                      << (guide ? guideDescription(o.guide, *guide) : std::string("the scene's path")) << "\n";
        }
        if (model->palpation()) std::cout << "  palpation on: the skin map is felt away from the entry\n";
        std::cout << "\n" << haptic::insertionSummaryText(r, inst.layers()) << "\noutputs:\n";
        printOutputs(std::cout, files);
    }
    if (!files.plotted && !o.noPlot) std::cerr << "voxhap simulate: no plot: " << files.plotWhy << '\n';
    return 0;
}

} // namespace

Action registerSimulate(CLI::App& app)
{
    auto o = std::make_shared<SimulateOptions>();
    std::string names;
    for (const auto& n : haptic::builtinSceneNames()) names += (names.empty() ? "" : ", ") + n;
    CLI::App* cmd = app.add_subcommand(
        "simulate", "Insert a needle through a scene's force model: CSV, force-depth PNG and a summary");
    cmd->add_option("volume", o->input,
        "A labelled volume (.vdb, .nrrd, .nii, .mha, DICOM folder), or a phantom: "
        "lumbar[:average|overweight|calcified], "
        "torso (default: the scene's)");
    cmd->add_option("--scene", o->scene, "Scene: a JSON file or a built-in name (" + names + ")")->required();
    cmd->add_option("--entry", o->entry, "Entry point on the skin x,y,z [mm, LPS] (default: the scene's)");
    cmd->add_option("--target", o->target, "Target x,y,z [mm, LPS] (default: the scene's)");
    cmd->add_option("--speed", o->speed, "Constant insertion speed [mm/s] (default: the scene's)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--depth", o->depth, "Insert this far past the entry [mm] (default: to the target)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--script", o->script,
        "Scripted motion: a CSV of t_s,depth_mm rows (depth past the entry), or t_s,depth_mm,roll_deg "
        "(the needle turned about its axis: a bending needle's bevel turns with it)");
    cmd->add_option("--rate", o->rate, "Servo rate [Hz] (default: the scene's, 1000)")->check(CLI::Range(1.0, 1e6));
    cmd->add_option("--out,-o", o->out, "Output directory (default voxhap-simulate)");
    cmd->add_flag("--no-plot", o->noPlot, "Skip the PNG");
    addGuideOptions(*cmd, o->guide);
    addCommonOptions(*cmd, o->common);
    return [o, cmd] { return run(*o, *cmd); };
}

} // namespace voxhap::tools
