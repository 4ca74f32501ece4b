// SPDX-License-Identifier: Apache-2.0
/// @file bench_plan.cpp
/// @brief Candidate search throughput (the planning target: ≥ 20 000 fully analysed
/// candidates per second on 2 cores), 1 and 2 threads interleaved in one run
/// (docs/benchmarks.md), with the clearance error of the same configuration
/// against brute force; and the bending needle's deflection prediction.
///
///     bench_plan [--repeats N] [--step DEG] [--spacing MM] [--ct DIR] [--target X,Y,Z]
///                [--prediction-step MM] [--prediction-nodes MM] [--json]
///
/// Workload: the torso phantom (its own labels, distance fields from
/// segmentation), the kyung scene, the vertebral lesion as target, directions
/// within 60° of posterior. Beside it, in the same run and interleaved, the
/// kyung-bending scene's search with and without the deflection prediction of
/// its 10 ranked paths (physics.md §9.6).
///
/// With --ct (the shared abdominal CT of docs/guide.md chapter 10, default
/// target 4,128,296, bone allowed, top 10): `voxhap plan`'s work without views,
/// load, segmentation, search, and the same with the prediction, interleaved:
/// their time ratio (target ≤ 1.15), and the prediction's error against the same
/// prediction at a fine step (0.05 mm per solve, 1 mm elements).

#include "haptic/scene/Scene.h"
#include "phantoms/Phantoms.h"
#include "planning/Deflection.h"
#include "planning/Search.h"
#include "segmentation/Segmentation.h"
#include "volume/Grids.h"
#include "volume/VolumeFile.h"

#include "bench/SamplerBench.h" // machineDescription
#include "bench/Stats.h"

#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

namespace {

using namespace voxhap;

/// Distance from segment a–b to the nearest voxel centre of @p id, by brute force [mm].
double bruteForce(const volume::Volume& v, int id, const Vec3d& a, const Vec3d& b)
{
    const auto labels = volume::labelGrid(v);
    const Vec3d ab = b - a;
    double best = std::numeric_limits<double>::infinity();
    for (auto it = labels->cbeginValueOn(); it; ++it) {
        if (*it != id) continue;
        const Vec3d p = volume::fromVdb(labels->indexToWorld(it.getCoord()));
        const double s = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
        best = std::min(best, (a + s * ab - p).norm());
    }
    return best;
}

/// `voxhap plan`'s work on a CT without its views (tools/commands/CmdPlan.cpp): load,
/// segment, search the top 10 with bone allowed, and, with @p predict, the
/// deflection of the ranked paths. @return the seconds it took; @p ranked the paths.
double planOnCt(const std::filesystem::path& ct, const Vec3d& target, const planning::DeflectionOptions* predict,
    std::vector<planning::TrajectoryReport>& ranked, std::shared_ptr<volume::Volume>* keep = nullptr)
{
    const auto& table = volume::TissueTable::builtin();
    const auto t0 = std::chrono::steady_clock::now();
    auto v = std::make_shared<volume::Volume>(volume::loadVolume(ct));
    segmentation::segment(*v, table, {});
    const planning::Planner planner(v, table, haptic::loadScene("kyung-bending"));
    planning::SearchConstraints k; // as plan's defaults, with --allow-bone
    k.allowBoneObstacles = true;
    planning::SearchOptions o;
    o.top = 10;
    ranked = planning::search(planner, target, k, o).ranked;
    if (predict) planning::predictDeflections(planner, ranked, *predict);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (keep) *keep = v;
    return s;
}

} // namespace

int main(int argc, char** argv)
{
    int repeats = 5;
    double step = 1.0, spacing = 1.0;
    bool json = false;
    std::string ct;
    Vec3d ctTarget(4.0, 128.0, 296.0);      // docs/guide.md chapter 10
    planning::DeflectionOptions prediction; // plan's
    for (int i = 1; i < argc; ++i) {
        const auto value = [&](const char* name) {
            if (i + 1 >= argc) {
                std::cerr << "bench_plan: error: " << name << " needs a value\n";
                std::exit(2);
            }
            return std::atof(argv[++i]);
        };
        if (!std::strcmp(argv[i], "--repeats"))
            repeats = std::max(1, int(value("--repeats")));
        else if (!std::strcmp(argv[i], "--step"))
            step = value("--step");
        else if (!std::strcmp(argv[i], "--spacing"))
            spacing = value("--spacing");
        else if (!std::strcmp(argv[i], "--json"))
            json = true;
        else if (!std::strcmp(argv[i], "--prediction-step"))
            prediction.stepMm = value("--prediction-step");
        else if (!std::strcmp(argv[i], "--prediction-nodes"))
            prediction.nodeSpacingMm = value("--prediction-nodes");
        else if (!std::strcmp(argv[i], "--ct") && i + 1 < argc)
            ct = argv[++i];
        else if (!std::strcmp(argv[i], "--target") && i + 1 < argc) {
            double x = 0, y = 0, z = 0;
            if (std::sscanf(argv[++i], "%lf,%lf,%lf", &x, &y, &z) != 3) {
                std::cerr << "bench_plan: error: --target needs x,y,z [mm]\n";
                return 2;
            }
            ctTarget = Vec3d(x, y, z);
        } else {
            std::cerr << "bench_plan: error: unknown option " << argv[i]
                      << " (--repeats N, --step DEG, --spacing MM, --ct DIR, --target X,Y,Z, --prediction-step MM, "
                         "--prediction-nodes MM, --json)\n";
            return 2;
        }
    }
    if (!(step > 0) || !(spacing > 0)) {
        std::cerr << "bench_plan: error: --step and --spacing must be positive\n";
        return 2;
    }

    const auto& table = volume::TissueTable::builtin();
    volume::GridSpec grid;
    grid.spacing = Vec3d::Constant(spacing);
    auto v = std::make_shared<volume::Volume>(volume::makePhantom(volume::torsoModel({}, table), grid, table));
    segmentation::SegmentOptions so;
    so.automatic = false;
    segmentation::segment(*v, table, so);
    const planning::Planner planner(v, table, haptic::loadScene("kyung"));
    const Vec3d lesion = *volume::phantomLandmark(*v, "lesion");
    planning::SearchConstraints k;
    k.reference = Vec3d(0, 1, 0);
    k.maxAngleDeg = 60.0;
    planning::SearchOptions o;
    o.stepDeg = step;

    // Interleaved: 1 thread, 2 threads, 1, 2, ... so drifting load hits both alike.
    std::vector<double> rate[2], ratio;
    planning::SearchResult last;
    (void)planning::search(planner, lesion, k, o); // warm-up: page in the grids
    for (int r = 0; r < repeats; ++r) {
        double perThreads[2] = {0, 0};
        for (int t = 0; t < 2; ++t) {
            tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(t + 1));
            last = planning::search(planner, lesion, k, o);
            perThreads[t] = double(last.counts.analysed) / last.seconds;
            rate[t].push_back(perThreads[t]);
        }
        ratio.push_back(perThreads[1] / perThreads[0]);
    }
    const bench::SampleStats one = bench::sampleStats(rate[0]), two = bench::sampleStats(rate[1]),
                             speedup = bench::sampleStats(ratio);

    // The bending needle's prediction: the search alone, then the search and the
    // prediction of its ranked paths, interleaved, both threads.
    const planning::Planner bending(v, table, haptic::loadScene("kyung-bending"));
    std::vector<double> searchS, predictS, predictRatio;
    (void)planning::search(bending, lesion, k, o);
    for (int r = 0; r < repeats; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        (void)planning::search(bending, lesion, k, o);
        const auto t1 = std::chrono::steady_clock::now();
        planning::SearchResult found = planning::search(bending, lesion, k, o);
        planning::predictDeflections(bending, found.ranked);
        const auto t2 = std::chrono::steady_clock::now();
        searchS.push_back(std::chrono::duration<double>(t1 - t0).count());
        predictS.push_back(std::chrono::duration<double>(t2 - t1).count());
        predictRatio.push_back(predictS.back() / searchS.back());
    }
    const bench::SampleStats plain = bench::sampleStats(searchS), withPrediction = bench::sampleStats(predictS),
                             predictionRatio = bench::sampleStats(predictRatio);

    // `plan` on the CT, without and with the prediction, interleaved; then the
    // prediction's error against a fine step on the same ranked paths.
    nlohmann::json ctJson;
    if (!ct.empty()) {
        std::vector<double> withoutS, withS, planRatio;
        std::vector<planning::TrajectoryReport> ranked;
        std::shared_ptr<volume::Volume> kept;
        (void)planOnCt(ct, ctTarget, nullptr, ranked); // warm-up: the files in the page cache
        for (int r = 0; r < repeats; ++r) {
            withoutS.push_back(planOnCt(ct, ctTarget, nullptr, ranked));
            withS.push_back(planOnCt(ct, ctTarget, &prediction, ranked, &kept));
            planRatio.push_back(withS.back() / withoutS.back());
        }
        const planning::Planner ctPlanner(kept, table, haptic::loadScene("kyung-bending"));
        planning::DeflectionOptions fine;
        fine.stepMm = 0.05;
        fine.nodeSpacingMm = 1.0;
        double worst = 0.0, largest = 0.0;
        for (const auto& p : ranked) {
            if (!p.deflection) continue;
            const auto ref = planning::predictDeflection(ctPlanner, p, fine);
            for (std::size_t i = 0; i < p.deflection->tried.size(); ++i) {
                const double e = std::abs(p.deflection->tried[i].tipDeviationMm - ref->tried[i].tipDeviationMm);
                if (std::getenv("BENCH_PLAN_DEBUG") && e > 0.1)
                    std::fprintf(stderr, "orientation %.0f turn %.0f: %.3f against %.3f\n",
                        p.deflection->tried[i].orientationDeg, p.deflection->tried[i].turnDepthMm,
                        p.deflection->tried[i].tipDeviationMm, ref->tried[i].tipDeviationMm);
                worst = std::max(worst, e);
                largest = std::max(largest, ref->tried[i].tipDeviationMm);
            }
        }
        const bench::SampleStats a = bench::sampleStats(withoutS), b = bench::sampleStats(withS),
                                 q = bench::sampleStats(planRatio);
        ctJson = {{"volume", ct}, {"target", {ctTarget.x(), ctTarget.y(), ctTarget.z()}}, {"scene", "kyung-bending"},
            {"paths", ranked.size()}, {"plan_s_median", a.median}, {"plan_with_prediction_s_median", b.median},
            {"ratio", {{"median", q.median}, {"sd", q.sd}}}, {"target_ratio", 1.15},
            {"prediction_step_mm", prediction.stepMm}, {"prediction_node_spacing_mm", prediction.nodeSpacingMm},
            {"tip_deviation_max_abs_error_mm", worst}, {"tip_deviation_largest_mm", largest},
            {"reference", "the same prediction at 0.05 mm per solve on 1 mm elements"}};
    }

    // Error of the same configuration: the best path's clearances against brute force
    // to voxel centres, less the half voxel between centre and surface (DistanceField.h).
    double maxErr = 0;
    nlohmann::json errors = nlohmann::json::object();
    if (!last.ranked.empty()) {
        const auto& best = last.ranked.front();
        for (const auto& c : best.clearances) {
            if (c.beyondBand) continue;
            const double ref = bruteForce(*v, table.at(c.tissue).id, best.entry, best.target) - 0.5 * spacing;
            errors[c.tissue] = c.minMm - ref;
            maxErr = std::max(maxErr, std::abs(c.minMm - ref));
        }
    }

    const std::string cpu = bench::machineDescription();
    if (json) {
        nlohmann::json j{{"benchmark", "plan-search"},
            {"machine", {{"cpu", cpu}, {"hardware_threads", std::thread::hardware_concurrency()}}},
            {"workload",
                {{"phantom", "torso"}, {"spacing_mm", spacing}, {"scene", "kyung"}, {"step_deg", step},
                    {"max_angle_deg", k.maxAngleDeg}, {"directions", last.counts.directions},
                    {"analysed", last.counts.analysed}, {"feasible", last.counts.feasible}}},
            {"repeats", repeats},
            {"candidates_per_s_1_thread", {{"median", one.median}, {"mean", one.mean}, {"sd", one.sd}}},
            {"candidates_per_s_2_threads", {{"median", two.median}, {"mean", two.mean}, {"sd", two.sd}}},
            {"speedup_2_over_1", {{"median", speedup.median}, {"sd", speedup.sd}}}, {"clearance_error_mm", errors},
            {"clearance_max_abs_error_mm", maxErr},
            {"bending_prediction",
                {{"scene", "kyung-bending"}, {"paths", o.top}, {"search_s_median", plain.median},
                    {"search_and_prediction_s_median", withPrediction.median},
                    {"ratio", {{"median", predictionRatio.median}, {"sd", predictionRatio.sd}}}}}};
        if (!ctJson.is_null()) j["bending_prediction_ct"] = ctJson;
        std::cout << j.dump(2) << '\n';
        return 0;
    }
    std::cout << "bench_plan: candidate search on the torso phantom (" << spacing << " mm voxels), kyung scene\n"
              << "machine: " << cpu << ", " << std::thread::hardware_concurrency() << " hardware threads\n"
              << "grid: " << step << " deg within " << k.maxAngleDeg << " deg of posterior: " << last.counts.directions
              << " directions, " << last.counts.analysed << " analysed, " << last.counts.feasible << " feasible; "
              << repeats << " repeats\n\n";
    std::printf("%-10s %14s %14s %10s\n", "threads", "median cand/s", "mean cand/s", "sd");
    std::printf("%-10d %14.0f %14.0f %10.0f\n", 1, one.median, one.mean, one.sd);
    std::printf("%-10d %14.0f %14.0f %10.0f\n", 2, two.median, two.mean, two.sd);
    std::printf("speed-up 2/1 threads (same run, interleaved): %.2f +- %.2f\n", speedup.median, speedup.sd);
    std::printf("clearance error of the best path vs brute force: max %.2f mm\n", maxErr);
    std::printf("kyung-bending: search %.3f s, with the deflection of its %d ranked paths %.3f s: ratio %.3f +- %.3f\n",
        plain.median, o.top, withPrediction.median, predictionRatio.median, predictionRatio.sd);
    if (!ctJson.is_null()) {
        std::printf("plan on %s to (%.0f, %.0f, %.0f), kyung-bending, top %d, no views: %.2f s, with the deflection "
                    "prediction %.2f s: ratio %.3f +- %.3f (target <= 1.15); the prediction's tip deviations within "
                    "%.3f mm of a fine step's (largest %.1f mm)\n",
            ct.c_str(), ctTarget.x(), ctTarget.y(), ctTarget.z(), int(ctJson["paths"]), double(ctJson["plan_s_median"]),
            double(ctJson["plan_with_prediction_s_median"]), double(ctJson["ratio"]["median"]),
            double(ctJson["ratio"]["sd"]), double(ctJson["tip_deviation_max_abs_error_mm"]),
            double(ctJson["tip_deviation_largest_mm"]));
    }
    return 0;
}
