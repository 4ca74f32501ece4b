// SPDX-License-Identifier: Apache-2.0
/// @file CmdInfo.cpp
/// @brief `voxhap info <file>`: describe a volume (.vdb or a DICOM series).

#include "tools/Cli.h"
#include "tools/InfoReport.h"
#include "tools/LoadOptions.h"

#include "volume/VolumeFile.h"

#include <iostream>
#include <memory>

namespace voxhap::tools {

namespace {

struct InfoOptions {
    CommonOptions common;
    ReaderOptions reader;
    std::string file;
};

nlohmann::json seriesJson(const std::vector<volume::DicomSeriesInfo>& all)
{
    nlohmann::json list = nlohmann::json::array();
    for (const auto& s : all) {
        list.push_back({{"uid", s.uid}, {"modality", s.modality}, {"description", s.description},
                        {"number", s.number}, {"rows", s.rows}, {"columns", s.columns}, {"slices", s.slices}});
    }
    return list;
}

int run(const InfoOptions& o)
{
    const volume::TissueTable& table = tissueTable(o.common);
    volume::DicomLoadReport dicom;
    const volume::Volume v = loadVolumeWithProgress(o.file, o.reader, stderrIsTerminal() && !o.common.json, &dicom);
    const auto info = volume::describe(v, table);
    if (o.common.json) {
        nlohmann::json j = infoJson(info, o.file);
        if (!dicom.allSeries.empty()) {
            j["dicom_series"] = seriesJson(dicom.allSeries);
            j["dicom_loaded_series"] = dicom.series.uid;
            j["load_seconds"] = dicom.seconds;
        }
        std::cout << j.dump(2) << '\n';
        return 0;
    }
    if (dicom.allSeries.size() > 1) {
        std::cout << "DICOM series in " << o.file << " (choose with --series UID or number):\n";
        for (std::size_t n = 0; n < dicom.allSeries.size(); ++n) {
            const auto& s = dicom.allSeries[n];
            std::cout << "  " << n + 1 << (s.uid == dicom.series.uid ? " * " : "   ") << s.modality << ' ' << s.columns << 'x'
                      << s.rows << 'x' << s.slices << "  " << s.uid << (s.description.empty() ? "" : "  \"" + s.description + "\"")
                      << '\n';
        }
        std::cout << '\n';
    }
    printInfo(std::cout, info, o.file);
    return 0;
}

} // namespace

Action registerInfo(CLI::App& app)
{
    auto o = std::make_shared<InfoOptions>();
    CLI::App* cmd = app.add_subcommand("info", "Describe a volume: grids, geometry, sparsity, memory, values, labels, layers");
    cmd->add_option("file", o->file, "Volume: a DICOM directory or file, .nii/.nii.gz, .nrrd, .mha/.mhd or .vdb")->required();
    addReaderOptions(*cmd, o->reader);
    addCommonOptions(*cmd, o->common);
    return [o] { return run(*o); };
}

} // namespace voxhap::tools
