// SPDX-License-Identifier: Apache-2.0
/// @file bench_volume.cpp
/// @brief Phantom rasterisation throughput and .vdb save/load time.
///
/// Run: build/bin/bench_volume [--benchmark_repetitions=5]. Figures are
/// reported per voxel of the dense extent, so that spacings compare.

#include "phantoms/Phantoms.h"
#include "volume/io/VdbFile.h"

#include <benchmark/benchmark.h>

#include <filesystem>
#include <unistd.h>

namespace {

using namespace voxhap;
using namespace voxhap::volume;

/// Rasterise @p model at a spacing of range(0)/100 mm, reporting dense voxels per second.
void rasteriseModel(benchmark::State& state, const PhantomModel& model)
{
    const TissueTable& table = TissueTable::builtin();
    GridSpec grid;
    grid.spacing = Vec3d::Constant(double(state.range(0)) / 100.0);
    std::int64_t voxels = 0;
    for (auto _ : state) {
        Volume v = makePhantom(model, grid, table);
        voxels = v.indexBox().voxelCount();
        benchmark::DoNotOptimize(v);
    }
    state.counters["voxels"] = double(voxels);
    state.counters["voxels/s"] = benchmark::Counter(double(voxels), benchmark::Counter::kIsIterationInvariantRate);
}

void BM_LumbarPhantom(benchmark::State& state)
{
    rasteriseModel(state, lumbarModel(LumbarParams{}, TissueTable::builtin()));
}
BENCHMARK(BM_LumbarPhantom)->Arg(100)->Arg(50)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_TorsoPhantom(benchmark::State& state)
{
    rasteriseModel(state, torsoModel(TorsoParams{}, TissueTable::builtin()));
}
BENCHMARK(BM_TorsoPhantom)->Arg(100)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_VdbRoundTrip(benchmark::State& state)
{
    const TissueTable& table = TissueTable::builtin();
    const LumbarParams p;
    const Volume v = makePhantom(lumbarModel(p, table), p.grid, table);
    const auto file = std::filesystem::temp_directory_path() / ("voxhap-bench-" + std::to_string(::getpid()) + ".vdb");
    for (auto _ : state) {
        saveVdb(v, file);
        Volume back = loadVdb(file);
        benchmark::DoNotOptimize(back);
    }
    std::filesystem::remove(file);
    state.counters["dense_voxels"] = double(v.indexBox().voxelCount());
}
BENCHMARK(BM_VdbRoundTrip)->Unit(benchmark::kMillisecond)->UseRealTime();

} // namespace

BENCHMARK_MAIN();
