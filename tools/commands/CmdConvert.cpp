// SPDX-License-Identifier: Apache-2.0
/// @file CmdConvert.cpp
/// @brief `voxhap convert <in> <out.vdb|out.nrrd>`: read any supported input,
/// write a sparse .vdb or a .nrrd for 3D Slicer, and report what was loaded.

#include "tools/Cli.h"
#include "tools/LoadOptions.h"

#include "volume/VolumeFile.h"
#include "volume/VolumeInfo.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <iomanip>
#include <iostream>
#include <memory>

namespace voxhap::tools {

namespace {

struct ConvertOptions {
    CommonOptions common;
    ReaderOptions reader;
    std::string in, out;
};

int run(const ConvertOptions& o)
{
    const auto outFormat = volume::formatOf(o.out);
    if (outFormat != volume::VolumeFormat::Vdb && outFormat != volume::VolumeFormat::Nrrd) {
        throw UsageError("output '" + o.out + "': expected a .vdb or .nrrd file name");
    }
    const auto start = std::chrono::steady_clock::now();
    volume::DicomLoadReport dicom;
    const volume::Volume v = loadVolumeWithProgress(o.in, o.reader, stderrIsTerminal() && !o.common.json, &dicom);
    const double loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    volume::saveVolume(v, o.out);
    const auto info = volume::describe(v, tissueTable(o.common));
    const double activeFraction = info.denseVoxels ? double(info.activeVoxels) / double(info.denseVoxels) : 0.0;
    const double denseFloatBytes = double(info.denseVoxels) * sizeof(float);
    const Vec3i d = info.box.dims();

    if (o.common.json) {
        nlohmann::json j;
        j["input"] = o.in;
        j["output"] = o.out;
        j["format"] = volume::formatName(volume::formatOf(o.in));
        j["dims"] = {d.x(), d.y(), d.z()};
        j["spacing_mm"] = {info.geometry.spacing.x(), info.geometry.spacing.y(), info.geometry.spacing.z()};
        j["load_seconds"] = loadSeconds;
        j["active_voxels"] = info.activeVoxels;
        j["dense_voxels"] = info.denseVoxels;
        j["active_fraction"] = activeFraction;
        j["memory_bytes"] = info.memoryBytes;
        j["memory_vs_dense_float"] = denseFloatBytes > 0 ? double(info.memoryBytes) / denseFloatBytes : 0.0;
        if (!dicom.series.uid.empty()) {
            j["series_uid"] = dicom.series.uid;
            j["series_index"] = dicom.series.index;
            j["series_count"] = dicom.allSeries.size();
            if (dicom.volume) j["volume"] = dicom.volume;
            j["resampled"] = dicom.resampled;
            if (dicom.resampled) {
                j["interpolation"] = dicom.interpolation;
                j["source_voxels_outside_grid"] = dicom.sourceVoxelsOutside;
            }
            j["skipped_files"] = dicom.skipped.size();
            j["skipped_bad_files"] = dicom.skippedBad.size();
        }
        if (v.metadata().mrWeighting) j["mr_weighting"] = volume::mrWeightingName(*v.metadata().mrWeighting);
        j["modality_source"] = volume::factSourceName(v.metadata().modalitySource);
        if (!v.metadata().modalityReason.empty()) j["modality_reason"] = v.metadata().modalityReason;
        std::cout << j.dump(2) << '\n';
        return 0;
    }
    std::cout << std::fixed << std::setprecision(3);
    std::cout << "read   " << o.in << " (" << volume::formatName(volume::formatOf(o.in)) << ") in " << loadSeconds
              << " s\n";
    if (!dicom.series.uid.empty()) {
        std::cout << "series #" << dicom.series.index << " " << dicom.series.uid << " (" << dicom.series.modality
                  << ", " << dicom.series.slices << " slices"
                  << (dicom.volume ? ", volume " + std::to_string(dicom.volume) : "") << "; " << dicom.allSeries.size()
                  << " series in the input, " << dicom.skipped.size() << " file(s) set aside)\n";
        if (dicom.resampled) {
            std::cout << "resampled: " << dicom.irregularity << "\n          " << dicom.interpolation
                      << "; source voxels outside the grid: " << dicom.sourceVoxelsOutside << "\n";
        }
        for (const auto& s : dicom.skippedBad) std::cout << "left out (--skip-bad): " << s.reason << "\n";
    }
    if (v.metadata().mrWeighting) {
        std::cout << "MR     " << volume::mrWeightingName(*v.metadata().mrWeighting) << " -> "
                  << (v.has(volume::Channel::T1) ? "t1 [ms]" : "intensity (not T1)") << "\n";
    }
    if (!v.metadata().modalityReason.empty()) {
        std::cout << "modality " << v.metadata().modality << ": " << v.metadata().modalityReason << "\n";
    }
    std::cout << "grid   " << d.x() << " x " << d.y() << " x " << d.z() << " voxels, spacing "
              << info.geometry.spacing.x() << " x " << info.geometry.spacing.y() << " x " << info.geometry.spacing.z()
              << " mm\n";
    std::cout << std::setprecision(1) << "active " << 100.0 * activeFraction << " % of the voxels; grid memory "
              << double(info.memoryBytes) / double(1 << 20)
              << " MiB (a dense float array: " << denseFloatBytes / double(1 << 20) << " MiB)\n";
    std::cout << "wrote  " << o.out << "\n";
    return 0;
}

} // namespace

Action registerConvert(CLI::App& app)
{
    auto o = std::make_shared<ConvertOptions>();
    CLI::App* cmd = app.add_subcommand("convert",
        "Convert a volume (DICOM series, NIfTI, NRRD, MetaImage, .vdb) to a sparse .vdb or a .nrrd for 3D Slicer");
    cmd->add_option("in", o->in, "Input: a DICOM directory or file, .nii/.nii.gz, .nrrd, .mha/.mhd or .vdb")
        ->required();
    cmd->add_option("out", o->out, "Output file: .vdb (all grids) or .nrrd (hu, else t1, else label)")->required();
    addReaderOptions(*cmd, o->reader);
    addCommonOptions(*cmd, o->common);
    return [o] { return run(*o); };
}

} // namespace voxhap::tools
