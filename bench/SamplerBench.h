// SPDX-License-Identifier: Apache-2.0
/// @file SamplerBench.h
/// @brief The runtime-versus-error table of docs benchmarks.md for shaft
/// integration: every strategy and step, with the dense-array and VTK
/// baselines measured in the same run, interleaved.
#pragma once

#include "core/Progress.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace voxhap::bench {

struct SamplerBenchOptions {
    /// "slab" (R1 closed form), "torso" (phantom), "ct" (ctDir, segmented, β per
    /// label), "mr" (mrDir, T1-weighted, β from T1 voxel by voxel)
    std::vector<std::string> workloads{"slab", "torso"};
    std::filesystem::path ctDir; ///< the real CT workload's DICOM folder or volume file
    std::filesystem::path mrDir; ///< the real MR workload's DICOM folder or volume file
    int paths = 48;              ///< shaft directions per workload (tilt 0..60°)
    int depths = 40;             ///< insertion depths per path, up to 100 mm
    int repetitions = 5;         ///< interleaved rounds over all configurations
    double speedMmPerS = 10.0;   ///< insertion speed for force errors [mm/s]
    double spacingMm = 0.5;      ///< phantom voxel size [mm]
    bool vtk = true;             ///< include the vtkProbeFilter baseline (slow)
    int fidelityPaths = 10000;   ///< random paths per workload for the error statistics (0: none)
    int fidelityDepths = 10;     ///< depths per fidelity path, up to 100 mm
};

/// @brief One configuration's figures.
struct SamplerRow {
    std::string workload;
    std::string config;              ///< e.g. "exact-voxel", "vdb march-trilinear 1/4", "dense march-trilinear 1/4"
    std::string reading;             ///< "voxel" or "trilinear": the interpretation it approximates
    double nsMedian = 0, nsP99 = 0;  ///< per evaluation, over per-path batches
    double errMaxN = 0, errRmsN = 0; ///< against the piecewise-constant reference [N]
    double errTriMaxN = 0, errTriRmsN = 0; ///< against the trilinear reference [N]
    long evaluations = 0;
};

/// @brief One strategy's error over the path-based fidelity sample [N].
struct FidelityRow {
    std::string workload, config, reading;
    long paths = 0, evaluations = 0;
    double nsMedian = 0;                          ///< from the timed table of the same run
    double rmsN = 0, p99N = 0, maxN = 0;          ///< against the exact reference of its reading
    double triRmsN = 0, triP99N = 0, triMaxN = 0; ///< against the exact trilinear reading
};

/// @brief Per workload, the ratios and checks the targets are judged by, measured in one run.
struct WorkloadSummary {
    std::string workload;
    double marchOverExact = 0;    ///< dense trilinear march at 1/4 voxel over exact voxel (median times)
    double marchOverProfile = 0;  ///< the same march over the locked profile
    double exactOverPeer = 0;     ///< exact voxel over the two-level OpenVDB block DDA peer
    double profileDeviationN = 0; ///< largest |profile − exact voxel| on the locked paths at the options' speed [N]
    double sumsRelativeDifference = 0; ///< largest |peer − exact| / |exact|
    /// Largest relative error of each against the plane-crossing sum in long double, and
    /// the largest error as a share of β_max·length (the sum's scale; tiny sums inflate the former).
    double exactRelativeError = 0, peerRelativeError = 0, exactScaledError = 0, peerScaledError = 0;
};

struct SamplerReport {
    std::string machine; ///< CPU model and core count
    SamplerBenchOptions options;
    std::vector<SamplerRow> rows;
    std::vector<FidelityRow> fidelity;    ///< path-based error statistics
    std::vector<WorkloadSummary> summary; ///< per workload: ratios and checks
    std::vector<std::string> notes;       ///< ratios and targets, measured in this run
};

/// @brief Run the benchmark; @p progress receives one line per stage.
SamplerReport runSamplerBench(const SamplerBenchOptions& options, const Progress& progress);

/// @brief The table as plain text.
void printSamplerReport(std::ostream& os, const SamplerReport& r);
/// @brief The report as JSON (for comparisons across commits).
nlohmann::json samplerReportJson(const SamplerReport& r);
/// @brief The strategy family of a configuration ("exact", "peer", "profile",
/// "vdb march-nearest", ..., "vtkProbeFilter"): the plot's legend.
std::string strategyFamily(const std::string& config);
/// @brief Per row, whether it is on its workload's Pareto front of median time
/// against the maximum error against the exact trilinear reading (no other row
/// as fast and as accurate, and better on one). Build rows are never on it.
std::vector<bool> paretoFront(const std::vector<SamplerRow>& rows);
/// @brief Log–log plot per workload, time against error, points coloured by
/// strategy family and the Pareto front drawn (gnuplot, pngcairo).
/// @return false with @p why set if gnuplot is missing or fails.
bool plotSamplerReport(const SamplerReport& r, const std::string& pngFile, std::string& why);

/// @brief "model name (N cores)" from /proc/cpuinfo.
std::string machineDescription();

} // namespace voxhap::bench
