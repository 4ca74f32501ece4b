// SPDX-License-Identifier: Apache-2.0
/// @file CmdDemo.cpp
/// @brief `voxhap demo`: the end-to-end job on a built-in phantom. For now:
/// generate the lumbar epidural phantom and describe it.

#include "tools/Cli.h"
#include "tools/InfoReport.h"

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
    const volume::Volume v = volume::makePhantom(volume::lumbarModel({}, table), volume::GridSpec{}, table);
    volume::saveVdb(v, file);
    const auto info = volume::describe(v, table);
    if (o.common.json) {
        std::cout << infoJson(info, file).dump(2) << '\n';
        return 0;
    }
    std::cout << "voxhap demo: lumbar epidural phantom (average patient, 0.5 mm voxels)\n\n";
    printInfo(std::cout, info, file);
    std::cout << "\noutputs:\n  " << file << "  (open with `voxhap info`, or in any OpenVDB viewer)\n";
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
