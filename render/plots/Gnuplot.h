// SPDX-License-Identifier: Apache-2.0
/// @file Gnuplot.h
/// @brief Draw a PNG with gnuplot (Debian's gnuplot-nox, pngcairo terminal):
/// the benchmark plots and the force–depth plots.
#pragma once

#include <filesystem>
#include <string>

namespace voxhap::render {

/// @brief A scratch directory for data files, removed on destruction.
class PlotDir {
public:
    PlotDir();
    ~PlotDir();
    PlotDir(const PlotDir&) = delete;
    PlotDir& operator=(const PlotDir&) = delete;
    const std::filesystem::path& path() const { return mDir; }

private:
    std::filesystem::path mDir;
};

/// @brief Run @p commands (everything after the terminal and output lines) to draw
/// @p pngFile of @p width × @p height pixels. The PNG appears complete or not at all.
/// @return false with @p why set when gnuplot is missing or fails
bool runGnuplot(const PlotDir& dir, const std::string& commands, const std::string& pngFile, int width, int height,
    std::string& why);

} // namespace voxhap::render
