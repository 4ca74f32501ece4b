// SPDX-License-Identifier: Apache-2.0
/// @file LoadOptions.cpp
/// @brief Reader options and the terminal progress bar.

#include "tools/LoadOptions.h"

#include "tools/Cli.h"

#include <cmath>
#include <iostream>

namespace voxhap::tools {

namespace {
bool gBarDrawn = false;
}

void addReaderOptions(CLI::App& cmd, ReaderOptions& o)
{
    cmd.add_option("--series", o.series,
                   "DICOM: SeriesInstanceUID or number (as listed by `voxhap info`) of the series to load "
                   "(default: the largest CT)");
    cmd.add_flag("--resample", o.resample,
                 "DICOM: resample uneven, gapped or tilted slice stacks onto a uniform grid (default: refuse them)");
    cmd.add_option("--air-hu", o.airHu, "CT voxels below this HU become inactive air (default -950)")
        ->check(CLI::Range(-2000.0, 0.0));
    cmd.add_option("--memory-cap", o.memoryCapMb, "Refuse inputs whose grid could exceed this many MiB (default 4096)")
        ->check(CLI::Range(1.0, 1e7));
    cmd.add_option("--channel", o.channel, "NRRD, MetaImage, NIfTI: the values are hu (CT) or t1 (MR) (default hu)")
        ->check(CLI::IsMember({"hu", "t1"}));
    cmd.add_flag("--t1-map", o.t1Map, "MR: the series is a T1 map in ms even if its headers do not say so");
}

volume::LoadOptions loadOptions(const ReaderOptions& o, bool showProgress)
{
    volume::LoadOptions l;
    l.dicom.series = o.series;
    l.dicom.irregular = o.resample ? volume::IrregularSlices::Resample : volume::IrregularSlices::Refuse;
    l.dicom.airHu = float(o.airHu);
    l.dicom.memoryCapBytes = std::uint64_t(o.memoryCapMb * double(1 << 20));
    l.dicom.t1Map = o.t1Map;
    l.channel = o.channel == "t1" ? volume::Channel::T1 : volume::Channel::Hu;
    if (showProgress) {
        l.dicom.progress = [](double f) {
            constexpr int kWidth = 40;
            const int filled = int(std::lround(f * kWidth));
            std::cerr << "\rloading [" << std::string(std::size_t(filled), '#') << std::string(std::size_t(kWidth - filled), ' ')
                      << "] " << int(std::lround(f * 100)) << "%" << std::flush;
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

volume::Volume loadVolumeWithProgress(const std::string& path, const ReaderOptions& opts, bool showProgress,
                                      volume::DicomLoadReport* report)
{
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
