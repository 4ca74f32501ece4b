// SPDX-License-Identifier: Apache-2.0
/// @file bench_dicom_load.cpp
/// @brief Loading a DICOM series into a sparse Volume against the bare GDCM
/// decode of the same files, measured interleaved in one run
/// (docs: benchmarks.md "Load"). Reports median seconds, the ratio, MB/s,
/// and the load's peak memory against a dense float array.
///
///   bench_dicom_load [DIR] [--repeat N] [--json FILE]
///   bench_dicom_load --loads-only N [DIR]   N loads and nothing else (for a profiler)
/// DIR defaults to ../shared/data/ct-abdomen-tcia/dicom beside the project.

#include "volume/dicom/DicomSeries.h"

#include <gdcmImageReader.h>
#include <gdcmTrace.h>
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <thread>
#include <unistd.h>
#include <vector>

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point a) { return std::chrono::duration<double>(Clock::now() - a).count(); }

double median(std::vector<double> v)
{
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

/// Read and decode every file with gdcm::ImageReader, nothing else.
std::size_t bareDecode(const std::vector<fs::path>& files, bool parallel)
{
    std::vector<std::size_t> bytes(files.size());
    const auto one = [&](std::size_t n) {
        gdcm::ImageReader r;
        r.SetFileName(files[n].string().c_str());
        if (!r.Read()) throw std::runtime_error(files[n].string() + ": GDCM cannot read it");
        std::vector<char> buf(r.GetImage().GetBufferLength());
        r.GetImage().GetBuffer(buf.data());
        bytes[n] = buf.size();
    };
    if (parallel)
        tbb::parallel_for(std::size_t(0), files.size(), one);
    else
        for (std::size_t n = 0; n < files.size(); ++n) one(n);
    std::size_t total = 0;
    for (auto b : bytes) total += b;
    return total;
}

/// /proc/self/status field in kB (VmRSS, VmHWM).
long statusKb(const char* key)
{
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind(key, 0) == 0) return std::stol(line.substr(std::string(key).size() + 1));
    }
    return -1;
}

/// Peak memory added by one load, measured in a fresh process (this program
/// re-run with --peak-only) so that the timing runs' freed heap, which a
/// forked child would inherit, does not hide it: VmHWM after the load minus
/// VmRSS before it.
double loadPeakBytes(const fs::path& dir, bool warm)
{
    const std::string cmd = "'/proc/" + std::to_string(::getpid()) + "/exe' " +
        (warm ? "--peak-warm '" : "--peak-only '") + dir.string() + "'";
    FILE* p = ::popen(cmd.c_str(), "r");
    if (!p) return -1;
    double peak = -1;
    if (std::fscanf(p, "%lf", &peak) != 1) peak = -1;
    ::pclose(p);
    return peak;
}

/// @param warm scan the headers first, so that GDCM's dictionaries (a fixed
///             cost of a few MiB, whatever the volume) are loaded before measuring
int peakOnly(const fs::path& dir, bool warm)
{
    if (warm) (void)voxhap::volume::listDicomSeries({dir});
    const long before = statusKb("VmRSS:");
    {
        const auto v = voxhap::volume::loadDicom({dir});
    }
    std::printf("%.0f\n", double(statusKb("VmHWM:") - before) * 1024.0);
    return 0;
}

std::string cpuModel()
{
    std::ifstream in("/proc/cpuinfo");
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
    }
    return "unknown";
}

} // namespace

int main(int argc, char** argv)
{
    fs::path dir = fs::path(VOXHAP_SOURCE_DIR) / ".." / "shared" / "data" / "ct-abdomen-tcia" / "dicom";
    int repeat = 7; // 7 interleaved repeats, medians (docs/benchmarks.md)
    std::string json;
    for (int a = 1; a < argc; ++a) {
        const std::string arg = argv[a];
        if (arg == "--peak-only" && a + 1 < argc) return peakOnly(argv[a + 1], false);
        if (arg == "--peak-warm" && a + 1 < argc) return peakOnly(argv[a + 1], true);
        if (arg == "--loads-only" && a + 1 < argc) { // for a profiler: loads and nothing else
            gdcm::Trace::SetWarning(false);
            const int n = std::max(1, std::atoi(argv[++a]));
            if (a + 1 < argc) dir = argv[a + 1];
            for (int r = 0; r < n; ++r) (void)voxhap::volume::loadDicom({dir});
            return 0;
        }
        if (arg == "--repeat" && a + 1 < argc)
            repeat = std::max(1, std::atoi(argv[++a]));
        else if (arg == "--json" && a + 1 < argc)
            json = argv[++a];
        else if (arg == "--help") {
            std::cout << "bench_dicom_load [DIR] [--repeat N] [--json FILE] | --loads-only N [DIR]\n";
            return 0;
        } else
            dir = arg;
    }
    try {
        gdcm::Trace::SetWarning(false);
        const auto series = voxhap::volume::listDicomSeries({dir});
        const auto& files = series.front().files;
        std::uint64_t fileBytes = 0;
        for (const auto& f : files) fileBytes += fs::file_size(f);

        std::vector<double> tSerial, tParallel, tLoad, tScan, tDecode, tSparse;
        voxhap::volume::DicomLoadReport report;
        (void)bareDecode(files, false);    // warm the page cache for every contender
        for (int r = 0; r < repeat; ++r) { // interleaved: each round runs all three
            auto t0 = Clock::now();
            const std::size_t pixelBytes = bareDecode(files, false);
            tSerial.push_back(seconds(t0));
            t0 = Clock::now();
            (void)bareDecode(files, true);
            tParallel.push_back(seconds(t0));
            t0 = Clock::now();
            {
                const auto v = voxhap::volume::loadDicom({dir}, {}, &report);
                tLoad.push_back(seconds(t0)); // until the volume is in hand, not counting its release
            }
            tScan.push_back(report.scanSeconds);
            tDecode.push_back(report.decodeSeconds);
            tSparse.push_back(report.sparseSeconds);
            (void)pixelBytes;
        }
        const double serial = median(tSerial), parallel = median(tParallel), load = median(tLoad);
        const double dense = double(report.denseVoxels) * sizeof(float);
        const double peak = loadPeakBytes(dir, false), peakWarm = loadPeakBytes(dir, true);

        std::printf("machine: %u hardware threads, %s\n", std::thread::hardware_concurrency(), cpuModel().c_str());
        std::printf("series:  %zu files, %.1f MB, %lld voxels, %d repetitions (medians)\n", files.size(),
            double(fileBytes) / 1e6, static_cast<long long>(report.denseVoxels), repeat);
        std::printf("%-34s %8s %8s %8s\n", "", "seconds", "MB/s", "ratio");
        std::printf("%-34s %8.3f %8.1f %8s\n", "bare GDCM decode, one thread", serial, double(fileBytes) / 1e6 / serial,
            "1.00");
        std::printf("%-34s %8.3f %8.1f %8.2f\n", "bare GDCM decode, TBB threads", parallel,
            double(fileBytes) / 1e6 / parallel, parallel / serial);
        std::printf("%-34s %8.3f %8.1f %8.2f\n", "voxhap loadDicom (sparse Volume)", load,
            double(fileBytes) / 1e6 / load, load / serial);
        std::printf("  of which: header scan %.3f s, decode %.3f s, sparse conversion %.3f s\n", median(tScan),
            median(tDecode), median(tSparse));
        // The load against the bare single-thread decode, same run.
        std::printf("load / bare decode, one thread: %.2f (target <= 1.2): %s\n", load / serial,
            load / serial <= 1.2 ? "met" : "not met");
        std::printf("load / bare decode with the same threads: %.2f\n", load / parallel);
        std::printf("active: %.1f %% of voxels; grid %.1f MiB; load peak %.1f MiB; dense float %.1f MiB\n",
            100.0 * double(report.activeVoxels) / double(report.denseVoxels), double(report.memoryBytes) / 1048576.0,
            peak / 1048576.0, dense / 1048576.0);
        std::printf("grid / dense float: %.2f; load peak / dense float: %.2f (target <= 0.6): %s\n",
            double(report.memoryBytes) / dense, peak / dense, peak / dense <= 0.6 ? "met" : "not met");
        std::printf("load peak with GDCM already initialised: %.1f MiB, %.2f of dense float\n", peakWarm / 1048576.0,
            peakWarm / dense);
        if (!json.empty()) {
            nlohmann::json j{{"files", files.size()}, {"file_bytes", fileBytes}, {"dense_voxels", report.denseVoxels},
                {"active_voxels", report.activeVoxels}, {"bare_decode_serial_s", serial},
                {"bare_decode_parallel_s", parallel}, {"load_s", load}, {"load_scan_s", median(tScan)},
                {"load_decode_s", median(tDecode)}, {"load_sparse_s", median(tSparse)},
                {"load_vs_parallel_decode", load / parallel}, {"load_vs_serial_decode", load / serial},
                {"load_vs_serial_decode_target", 1.2}, {"load_peak_vs_dense_target", 0.6},
                {"grid_bytes", report.memoryBytes}, {"load_peak_bytes", peak}, {"load_peak_warm_bytes", peakWarm},
                {"dense_float_bytes", dense}, {"hardware_threads", std::thread::hardware_concurrency()},
                {"cpu", cpuModel()}};
            std::ofstream(json) << j.dump(2) << '\n';
        }
    } catch (const std::exception& e) {
        std::cerr << "bench_dicom_load: error: " << e.what() << '\n';
        return 1;
    }
    return 0;
}
