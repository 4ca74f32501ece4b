// SPDX-License-Identifier: Apache-2.0
/// @file LoadOptions.cpp
/// @brief Reader options and the terminal progress bar.

#include "tools/LoadOptions.h"

#include "tools/Cli.h"

#include "core/BoundedRead.h"

#include <cmath>
#include <iostream>

namespace voxhap::tools {

namespace {
bool gBarDrawn = false;
}

void addReaderOptions(CLI::App& cmd, ReaderOptions& o)
{
    cmd.add_option("--series", o.series,
        "DICOM: the series to load: its SeriesInstanceUID, its SeriesNumber, or #N for row N of the "
        "table `voxhap info` prints (a plain N works when it names one series). Default: the largest "
        "series that loads as one 3D volume, CT first, then T1-weighted MR, then other MR");
    cmd.add_option("--volume", o.volume,
           "DICOM: which 3D volume of a 4D series (fMRI time point, diffusion direction, echo), from 1 in "
           "acquisition order as `voxhap info` lists them")
        ->check(CLI::Range(std::size_t(1), std::size_t(1000000)));
    cmd.add_flag("--resample", o.resample,
        "DICOM: resample uneven, gapped or tilted slice stacks onto a uniform grid that holds every source "
        "voxel (default: refuse them)");
    cmd.add_flag("--skip-bad", o.skipBad,
        "DICOM: load the rest of a series when some of its files cannot be read (listed); the gap checks "
        "then apply as usual");
    cmd.add_option("--air-hu", o.airHu, "CT voxels below this HU become inactive air (default -950)")
        ->check(CLI::Range(-2000.0, 0.0));
    cmd.add_option("--memory-cap", o.memoryCapMb, "Refuse inputs whose grid could exceed this many MiB (default 4096)")
        ->check(CLI::Range(1.0, 1e7));
    cmd.add_option("--channel", o.channel,
           "NRRD, MetaImage, NIfTI: what the values are: auto (a BIDS sidecar's Modality, else CT or MR "
           "inferred from the values), hu (CT), mr (MR intensities; T1 only with --t1-map, --t1-weighted or "
           "a sidecar that says T1-weighted); t1 is read as mr (default auto)")
        ->check(CLI::IsMember({"auto", "hu", "mr", "t1"}));
    cmd.add_flag("--t1-map", o.t1Map, "MR: the values are a T1 map in ms, whatever the headers say");
    cmd.add_flag("--t1-weighted", o.t1Weighted,
        "MR: declare the image T1-weighted, whatever the headers say (recorded in the metadata); its "
        "intensities are then normalised per scan to T1 [ms]");
}

volume::LoadOptions loadOptions(const ReaderOptions& o, bool showProgress)
{
    volume::LoadOptions l;
    l.dicom.series = o.series;
    l.dicom.volume = o.volume;
    l.dicom.skipBad = o.skipBad;
    l.dicom.t1Weighted = o.t1Weighted;
    l.dicom.irregular = o.resample ? volume::IrregularSlices::Resample : volume::IrregularSlices::Refuse;
    l.dicom.airHu = float(o.airHu);
    l.dicom.memoryCapBytes = std::uint64_t(o.memoryCapMb * double(1 << 20));
    l.dicom.t1Map = o.t1Map;
    l.modality = o.channel == "hu"               ? volume::DeclaredModality::Ct
        : o.channel == "mr" || o.channel == "t1" ? volume::DeclaredModality::Mr
                                                 : volume::DeclaredModality::Infer;
    if (showProgress) {
        l.dicom.progress = [](double f, std::string_view) {
            constexpr int kWidth = 40;
            const int filled = int(std::lround(f * kWidth));
            std::cerr << "\rloading [" << std::string(std::size_t(filled), '#')
                      << std::string(std::size_t(kWidth - filled), ' ') << "] " << int(std::lround(f * 100)) << "%"
                      << std::flush;
            gBarDrawn = true;
        };
    }
    return l;
}

void clearProgress()
{
    if (gBarDrawn) std::cerr << "\r\033[K" << std::flush;
    gBarDrawn = false;
}

volume::Volume loadVolumeWithProgress(
    const std::string& path, const ReaderOptions& opts, bool showProgress, volume::DicomLoadReport* report)
{
    // A FIFO or a device (/dev/zero, /dev/urandom) is refused before anything opens it.
    requireRegularFile(path, "volume", /*allowDirectory=*/true);
    try {
        auto loaded = volume::loadVolume(path, loadOptions(opts, showProgress), report);
        clearProgress();
        return loaded;
    } catch (...) {
        clearProgress();
        throw;
    }
}

} // namespace voxhap::tools
