// SPDX-License-Identifier: Apache-2.0
/// @file bench_segment.cpp
/// @brief Segmentation time and memory on the real CT, with 1 and 2 threads measured in the same run
/// (docs/benchmarks.md: speed with its error, comparisons as ratios from one run); the peak memory against the dense
/// float copy of the volume and against segmentation's own estimate; the load average and the CPU time beside the wall
/// time, because this machine is shared.
///
///     bench_segment [--repeats N] [--json]
///
/// Without ../shared/data the torso phantom (1 mm voxels) stands in, and the
/// report says so.

#include "phantoms/Phantoms.h"
#include "segmentation/Segmentation.h"
#include "volume/Grids.h"
#include "volume/VolumeFile.h"

#include "bench/ProcessFigures.h"
#include "bench/Stats.h"

#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

namespace {

using namespace voxhap;
using bench::cpuSeconds;
using bench::loadAverage;
using bench::peakRssMb;

} // namespace

int main(int argc, char** argv)
{
    int repeats = 3;
    bool json = false;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--repeats") && i + 1 < argc)
            repeats = std::max(1, std::atoi(argv[++i]));
        else if (!std::strcmp(argv[i], "--json"))
            json = true;
        else {
            std::cerr << "usage: bench_segment [--repeats N] [--json]\n";
            return 2;
        }
    }
    const auto& table = volume::TissueTable::builtin();
    const std::filesystem::path ct =
        std::filesystem::path(VOXHAP_SOURCE_DIR) / ".." / "shared" / "data" / "ct-abdomen-tcia" / "dicom";
    const bool real = std::filesystem::is_directory(ct);
    volume::TorsoParams tp;
    tp.grid.spacing = Vec3d(1, 1, 1);
    const volume::Volume input =
        real ? volume::loadVolume(ct) : volume::makePhantom(volume::torsoModel(tp, table), tp.grid, table);
    const double rssBefore = peakRssMb();
    const double denseFloatMb = double(input.indexBox().voxelCount()) * 4.0 / (1 << 20);

    // Measured first, before any run, so that the peak below is segmentation's own.
    const double estimateMb = double(segmentation::workingBytes(input)) / (1 << 20);
    const double inputMb = double(volume::huGrid(input) ? volume::huGrid(input)->memUsage() : 0) / (1 << 20);
    const double loadBefore = loadAverage();
    nlohmann::json out;
    out["machine"] = {{"hardware_threads", std::thread::hardware_concurrency()}};
    out["input"] = real ? "real CT (ct-abdomen-tcia)" : "torso phantom, 1 mm (real CT not found)";
    out["voxels"] = input.indexBox().voxelCount();
    std::vector<double> means;
    for (int threads : {1, 2}) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
        std::vector<double> t, cpu;
        for (int r = 0; r < repeats; ++r) {
            volume::Volume v = input; // grids are shared read-only; segment() adds its own
            const auto start = std::chrono::steady_clock::now();
            const double cpu0 = cpuSeconds();
            segmentation::segment(v, table);
            t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
            cpu.push_back(cpuSeconds() - cpu0);
        }
        const bench::SampleStats s = bench::sampleStats(t);
        means.push_back(s.mean);
        out["threads_" + std::to_string(threads)] = {{"mean_s", s.mean}, {"sd_s", s.sd}, {"median_s", s.median},
            {"cpu_s_mean", bench::sampleStats(cpu).mean}, {"repeats", repeats}};
    }
    out["speedup_2_vs_1"] = means[0] / means[1];
    out["peak_rss_mb"] = peakRssMb();
    out["peak_rss_over_load_mb"] = peakRssMb() - rssBefore;
    out["dense_float_mb"] = denseFloatMb;
    out["peak_rss_dense_copies"] = peakRssMb() / denseFloatMb;
    out["peak_rss_over_load_dense_copies"] = (peakRssMb() - rssBefore) / denseFloatMb;
    out["input_grid_mb"] = inputMb;
    out["working_estimate_mb"] = estimateMb;
    // The estimate covers what segment() adds: the peak above the loaded volume must stay under it.
    out["peak_over_load_within_estimate"] = peakRssMb() - rssBefore <= estimateMb;
    out["load_average"] = {{"before", loadBefore}, {"after", loadAverage()}};
    if (json) {
        std::cout << out.dump(2) << '\n';
        return 0;
    }
    std::cout << "segmentation of the " << out["input"].get<std::string>() << ", " << out["voxels"] << " voxels\n";
    for (int threads : {1, 2}) {
        const auto& j = out["threads_" + std::to_string(threads)];
        std::cout << "  " << threads << " thread" << (threads > 1 ? "s" : " ") << ": " << j["mean_s"].get<double>()
                  << " s ± " << j["sd_s"].get<double>() << " s (n = " << repeats << ")\n";
    }
    std::cout << "  2 vs 1 thread: " << out["speedup_2_vs_1"].get<double>() << "x\n";
    std::cout << "  working memory estimate: " << estimateMb << " MiB beside the volume's " << inputMb
              << " MiB; load average " << loadBefore << " before, " << out["load_average"]["after"].get<double>()
              << " after (2 cores: above 2, other processes took CPU)\n";
    std::cout << "  peak memory: " << out["peak_rss_mb"].get<double>() << " MiB ("
              << out["peak_rss_over_load_mb"].get<double>()
              << " MiB above the loaded volume; a dense float copy of it is " << denseFloatMb << " MiB)\n";
    return 0;
}
