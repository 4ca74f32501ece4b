// SPDX-License-Identifier: Apache-2.0
/// @file bench_render.cpp
/// @brief Four-view frame times of the viewer on the real CT and a 256³ phantom
/// (docs: benchmarks.md "Rendering"). Same as `voxhap bench render --ct DIR`.
///
///     bench_render [--ct DIR] [--first N] [--steady N] [--orbit-frames N] [--orbit-only] [--json FILE]
///
/// Without --ct, the real CT of ../shared/data is used when present.

#include "bench/RenderBench.h"

#include <algorithm>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

int main(int argc, char** argv)
{
    voxhap::bench::RenderBenchOptions o;
    const std::filesystem::path ct =
        std::filesystem::path(VOXHAP_SOURCE_DIR) / ".." / "shared" / "data" / "ct-abdomen-tcia" / "dicom";
    if (std::filesystem::is_directory(ct)) o.ct = ct.string();
    std::string json;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--ct" && i + 1 < argc)
            o.ct = argv[++i];
        else if (a == "--first" && i + 1 < argc)
            o.firstFrames = std::max(1, std::atoi(argv[++i]));
        else if (a == "--steady" && i + 1 < argc)
            o.steadyFrames = std::max(1, std::atoi(argv[++i]));
        else if (a == "--orbit-frames" && i + 1 < argc)
            o.orbitFrames = std::max(0, std::atoi(argv[++i]));
        else if (a == "--orbit-only")
            o.fourView = false;
        else if (a == "--json" && i + 1 < argc)
            json = argv[++i];
        else {
            std::cerr << "usage: bench_render [--ct DIR] [--first N] [--steady N] [--orbit-frames N] [--orbit-only] "
                         "[--json FILE]\n";
            return 2;
        }
    }
    try {
        const auto report = voxhap::bench::runRenderBench(o, [](double, std::string_view s) {
            if (!s.empty()) std::cerr << s << '\n';
        });
        voxhap::bench::printRenderReport(std::cout, report);
        if (!json.empty()) std::ofstream(json) << voxhap::bench::renderReportJson(report).dump(2) << '\n';
    } catch (const std::exception& e) {
        std::cerr << "bench_render: " << e.what() << '\n';
        return 1;
    }
    return 0;
}
