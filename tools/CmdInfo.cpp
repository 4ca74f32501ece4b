// SPDX-License-Identifier: Apache-2.0
/// @file CmdInfo.cpp
/// @brief `voxhap info <file>`: describe a volume.

#include "tools/Cli.h"
#include "tools/InfoReport.h"

#include "volume/VdbFile.h"

#include <iostream>
#include <memory>

namespace voxhap::tools {

namespace {

struct InfoOptions {
    CommonOptions common;
    std::string file;
};

int run(const InfoOptions& o)
{
    const volume::TissueTable& table = tissueTable(o.common);
    const volume::Volume v = volume::loadVdb(o.file);
    const auto info = volume::describe(v, table);
    if (o.common.json) std::cout << infoJson(info, o.file).dump(2) << '\n';
    else printInfo(std::cout, info, o.file);
    return 0;
}

} // namespace

Action registerInfo(CLI::App& app)
{
    auto o = std::make_shared<InfoOptions>();
    CLI::App* cmd = app.add_subcommand("info", "Describe a volume: grids, geometry, sparsity, memory, values, labels, layers");
    cmd->add_option("file", o->file, "Volume file (.vdb)")->required();
    addCommonOptions(*cmd, o->common);
    return [o] { return run(*o); };
}

} // namespace voxhap::tools
