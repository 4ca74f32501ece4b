// SPDX-License-Identifier: Apache-2.0
/// @file LoadOptions.h
/// @brief The reader options `voxhap info` and `voxhap convert` share
/// (series choice, irregular stacks, air threshold, memory cap), and the
/// progress bar shown on a terminal.
#pragma once

#include "volume/VolumeFile.h"

#include <CLI/CLI.hpp>

#include <string>

namespace voxhap::tools {

/// @brief Command-line form of volume::LoadOptions.
struct ReaderOptions {
    std::string series;           ///< --series
    std::size_t volume = 0;       ///< --volume (from 1; 0: the series must hold one)
    bool resample = false;        ///< --resample
    bool skipBad = false;         ///< --skip-bad
    double airHu = -950.0;        ///< --air-hu
    double memoryCapMb = 4096;    ///< --memory-cap [MiB]
    bool t1Map = false;           ///< --t1-map
    bool t1Weighted = false;      ///< --t1-weighted
    std::string channel = "auto"; ///< --channel
};

/// @brief Add the reader options to a subcommand.
void addReaderOptions(CLI::App& cmd, ReaderOptions& opts);

/// @brief The library options; progress goes to a bar on stderr when @p showProgress.
volume::LoadOptions loadOptions(const ReaderOptions& opts, bool showProgress);

/// @brief Erase the progress bar line, if one was drawn.
void clearProgress();

/// @brief volume::loadVolume() with the progress bar when @p showProgress, erased
/// afterwards whether the load succeeds or throws.
volume::Volume loadVolumeWithProgress(
    const std::string& path, const ReaderOptions& opts, bool showProgress, volume::DicomLoadReport* report = nullptr);

} // namespace voxhap::tools
