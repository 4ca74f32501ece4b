// SPDX-License-Identifier: Apache-2.0
/// @file Gnuplot.cpp
#include "render/plots/Gnuplot.h"

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <unistd.h>

namespace voxhap::render {

namespace fs = std::filesystem;

PlotDir::PlotDir()
{
    static std::atomic<int> counter{0};
    mDir = fs::temp_directory_path() /
        ("voxhap-plot-" + std::to_string(::getpid()) + "-" + std::to_string(counter.fetch_add(1)));
    fs::create_directories(mDir);
}

PlotDir::~PlotDir()
{
    std::error_code ignored;
    fs::remove_all(mDir, ignored);
}

bool runGnuplot(const PlotDir& dir, const std::string& commands, const std::string& pngFile, int width, int height,
    std::string& why)
{
    const std::string tmp = pngFile + ".tmp";
    {
        std::ofstream script(dir.path() / "plot.gp");
        script << "set terminal pngcairo size " << width << ',' << height << " font ',10'\n"
               << "set output '" << tmp << "'\n"
               << commands << "\nset output\n";
    }
    const std::string cmd =
        "gnuplot '" + (dir.path() / "plot.gp").string() + "' 2>'" + (dir.path() / "err.txt").string() + "'";
    const int rc = std::system(cmd.c_str());
    std::error_code ignored;
    if (rc == 0 && fs::exists(tmp) && fs::file_size(tmp, ignored) > 0) {
        fs::rename(tmp, pngFile);
        return true;
    }
    // gnuplot reports an error as the offending line, a caret, then the message: keep the message.
    std::ifstream err(dir.path() / "err.txt");
    for (std::string line; std::getline(err, line);) {
        if (line.find_first_not_of(" \t^") != std::string::npos) why = line;
    }
    why = "gnuplot failed" + (why.empty() ? std::string(" (is gnuplot-nox installed?)") : ": " + why);
    fs::remove(tmp, ignored);
    return false;
}

} // namespace voxhap::render
