// SPDX-License-Identifier: Apache-2.0
/// @file CmdPlot.cpp
/// @brief `voxhap plot <recording>`: the force–depth plot of a simulated
/// insertion (insertion.csv) or a served session (session.csv + events.csv),
/// with layer bands and events.

#include "tools/Cli.h"

#include "core/Errors.h"
#include "render/plots/ForcePlot.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <iostream>
#include <memory>

namespace voxhap::tools {

namespace {

namespace fs = std::filesystem;

struct PlotOptions {
    CommonOptions common;
    std::string input, out, title;
};

int run(const PlotOptions& o)
{
    render::ForceTrace trace = render::readForceTrace(o.input);
    if (!o.title.empty()) trace.title = o.title;
    const fs::path dir = fs::is_directory(o.input) ? fs::path(o.input) : fs::path(o.input).parent_path();
    const std::string png = o.out.empty() ? (dir / "force-depth.png").string() : o.out;
    std::string why;
    if (!render::plotForceDepth(trace, png, why)) throw IoError(png + ": " + why);
    if (o.common.json) {
        nlohmann::json j;
        j["input"] = o.input;
        j["png"] = png;
        j["samples"] = trace.samples.size();
        j["layers"] = trace.layers.size();
        j["events"] = trace.events.size();
        std::cout << j.dump(2) << '\n';
    } else {
        std::cout << "wrote  " << png << "  (" << trace.samples.size() << " samples, " << trace.layers.size()
                  << " layers, " << trace.events.size() << " events)\n";
    }
    return 0;
}

} // namespace

Action registerPlot(CLI::App& app)
{
    auto o = std::make_shared<PlotOptions>();
    CLI::App* cmd =
        app.add_subcommand("plot", "Force-depth PNG of a recording, with layer bands and events (needs gnuplot)");
    cmd->add_option("recording", o->input,
           "insertion.csv (voxhap simulate), session.csv (voxhap serve; events.csv beside it), or their folder")
        ->required()
        ->check(CLI::ExistingPath);
    cmd->add_option("--out,-o", o->out, "Output PNG (default: force-depth.png beside the recording)");
    cmd->add_option("--title", o->title, "Plot title (default: the folder and the kind of recording)");
    addCommonOptions(*cmd, o->common);
    return [o] { return run(*o); };
}

} // namespace voxhap::tools
