// SPDX-License-Identifier: Apache-2.0
/// @file bench_sampler.cpp
/// @brief The shaft-integration runtime-versus-error table (docs: benchmarks.md).
///
///   build/bin/bench_sampler [--quick] [--json FILE] [--png FILE] [--no-vtk]
/// Same as `voxhap bench sampler`.

#include "bench/SamplerBench.h"

#include <cstring>
#include <fstream>
#include <iostream>

int main(int argc, char** argv)
{
    voxhap::bench::SamplerBenchOptions o;
    std::string json, png;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--quick") {
            o.paths = 12;
            o.depths = 20;
            o.repetitions = 2;
        } else if (a == "--no-vtk") {
            o.vtk = false;
        } else if (a == "--json" && i + 1 < argc) {
            json = argv[++i];
        } else if (a == "--png" && i + 1 < argc) {
            png = argv[++i];
        } else {
            std::cerr << "usage: bench_sampler [--quick] [--no-vtk] [--json FILE] [--png FILE]\n";
            return 2;
        }
    }
    const auto report = voxhap::bench::runSamplerBench(o, [](double, std::string_view s) { std::cerr << s << '\n'; });
    voxhap::bench::printSamplerReport(std::cout, report);
    if (!json.empty()) std::ofstream(json) << voxhap::bench::samplerReportJson(report).dump(2) << '\n';
    if (!png.empty()) {
        std::string why;
        if (!voxhap::bench::plotSamplerReport(report, png, why)) std::cerr << "bench_sampler: " << why << '\n';
    }
    return 0;
}
