// SPDX-License-Identifier: Apache-2.0
/// @file bench_sampler.cpp
/// @brief The shaft-integration runtime-versus-error table (docs: benchmarks.md).
///
///   build/bin/bench_sampler [--quick] [--json FILE] [--png FILE] [--no-vtk]
///                           [--workloads slab,torso,ct,mr] [--ct DIR] [--mr DIR]
///                           [--fidelity-paths N]
/// Same as `voxhap bench sampler`, with the real workloads on by default: the
/// shared CT and T1-weighted MR beside the project (../shared/data).

#include "bench/SamplerBench.h"

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

int main(int argc, char** argv)
{
    voxhap::bench::SamplerBenchOptions o;
    const std::filesystem::path shared = std::filesystem::path(VOXHAP_SOURCE_DIR) / ".." / "shared" / "data";
    o.ctDir = shared / "ct-abdomen-tcia" / "dicom";
    o.mrDir = shared / "mr-head-trio" / "t1-mprage";
    o.workloads = {"slab", "torso", "ct", "mr"};
    std::string json, png;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--quick") {
            o.paths = 12;
            o.depths = 20;
            o.repetitions = 2;
            o.fidelityPaths = 1000;
        } else if (a == "--fidelity-paths" && i + 1 < argc) {
            o.fidelityPaths = std::atoi(argv[++i]);
        } else if (a == "--no-vtk") {
            o.vtk = false;
        } else if (a == "--workloads" && i + 1 < argc) {
            o.workloads.clear();
            std::stringstream list(argv[++i]);
            for (std::string w; std::getline(list, w, ',');) o.workloads.push_back(w);
        } else if (a == "--ct" && i + 1 < argc) {
            o.ctDir = argv[++i];
        } else if (a == "--mr" && i + 1 < argc) {
            o.mrDir = argv[++i];
        } else if (a == "--json" && i + 1 < argc) {
            json = argv[++i];
        } else if (a == "--png" && i + 1 < argc) {
            png = argv[++i];
        } else {
            std::cerr
                << "usage: bench_sampler [--quick] [--no-vtk] [--workloads slab,torso,ct,mr] [--ct DIR] [--mr DIR] "
                   "[--json FILE] [--png FILE]\n";
            return 2;
        }
    }
    voxhap::bench::SamplerReport report;
    try {
        report = voxhap::bench::runSamplerBench(o, [](double, std::string_view s) { std::cerr << s << '\n'; });
    } catch (const std::exception& e) {
        std::cerr << "bench_sampler: " << e.what() << '\n';
        return 1;
    }
    voxhap::bench::printSamplerReport(std::cout, report);
    if (!json.empty()) std::ofstream(json) << voxhap::bench::samplerReportJson(report).dump(2) << '\n';
    if (!png.empty()) {
        std::string why;
        if (!voxhap::bench::plotSamplerReport(report, png, why)) std::cerr << "bench_sampler: " << why << '\n';
    }
    return 0;
}
