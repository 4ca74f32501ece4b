// SPDX-License-Identifier: Apache-2.0
/// @file ServoBench.cpp
#include "bench/ServoBench.h"

#include "bench/SamplerBench.h"
#include "haptic/Scene.h"
#include "haptic/ServoLoop.h"
#include "haptic/SimulatedDevices.h"

#include <chrono>
#include <iomanip>
#include <map>
#include <memory>
#include <thread>

namespace voxhap::bench {

namespace {

/// One real-time run: a reckless hand at 5 mm/s goes through every layer of the path
/// (tenting, pops, LOR, dura) and on; the queues are drained as `voxhap serve` does.
ServoRun runOnce(const haptic::SceneInstance& inst, double rateHz, double seconds)
{
    auto model = inst.makeModel();
    haptic::HandParams p;
    p.speedMmPerS = 5.0;
    p.stopOnLor = false;
    haptic::HandDevice hand(model->path(), p, model->device());
    haptic::ServoOptions so;
    so.rateHz = rateHz;
    haptic::ServoLoop loop(*model, hand, so);
    const auto t0 = std::chrono::steady_clock::now();
    loop.start();
    haptic::ServoRecord rec;
    haptic::Event ev;
    while (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < seconds) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        while (loop.popRecord(rec)) {
        }
        while (loop.popEvent(ev)) {
        }
    }
    loop.stop();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ServoRun r;
    r.scene = inst.scene().name;
    r.rateHz = rateHz;
    r.seconds = wall;
    r.ticks = loop.ticks();
    r.achievedHz = double(r.ticks) / wall;
    r.overruns = loop.overruns();
    r.computeP50Ns = loop.stats().computeQuantileNs(0.5);
    r.computeP99Ns = loop.stats().computeQuantileNs(0.99);
    r.computeMaxNs = loop.maxComputeNs();
    r.periodErrP50Ns = loop.stats().jitterQuantileNs(0.5);
    r.periodErrP99Ns = loop.stats().jitterQuantileNs(0.99);
    return r;
}

} // namespace

ServoReport runServoBench(const ServoBenchOptions& o, void (*progress)(const std::string&))
{
    ServoReport report;
    report.machine = machineDescription();
    const auto& table = volume::TissueTable::builtin();
    for (const std::string& name : o.scenes) {
        if (progress) progress("building " + name);
        const haptic::SceneInstance inst(haptic::loadScene(name), nullptr, table);
        if (progress) progress(name + ": 1 kHz for " + std::to_string(int(o.seconds)) + " s");
        report.runs.push_back(runOnce(inst, 1000.0, o.seconds));
        double best = 0.0;
        for (const double rate : o.rates) {
            if (progress) progress(name + ": " + std::to_string(int(rate)) + " Hz");
            const ServoRun r = runOnce(inst, rate, o.ladderSeconds);
            report.ladder.push_back(r);
            // Sustained: the rate achieved within 1 % and fewer than 0.1 % of ticks overrun.
            if (r.achievedHz >= 0.99 * rate && double(r.overruns) <= 1e-3 * double(r.ticks)) best = rate;
        }
        report.sustainableHz.emplace_back(name, best);
    }
    return report;
}

void printServoReport(std::ostream& os, const ServoReport& r)
{
    os << "machine: " << r.machine << "\n\n";
    const auto row = [&](const ServoRun& x) {
        os << std::left << std::setw(16) << x.scene << std::right << std::fixed << std::setprecision(0) << std::setw(9)
           << x.rateHz << std::setw(10) << x.achievedHz << std::setw(9) << x.ticks << std::setw(9) << x.overruns
           << std::setprecision(2) << std::setw(10) << x.computeP50Ns * 1e-3 << std::setw(10) << x.computeP99Ns * 1e-3
           << std::setw(10) << x.computeMaxNs * 1e-3 << std::setw(10) << x.periodErrP50Ns * 1e-3 << std::setw(10)
           << x.periodErrP99Ns * 1e-3 << '\n';
    };
    const auto header = [&] {
        os << std::left << std::setw(16) << "scene" << std::right << std::setw(9) << "rate" << std::setw(10) << "achieved"
           << std::setw(9) << "ticks" << std::setw(9) << "overrun" << std::setw(10) << "p50 us" << std::setw(10)
           << "p99 us" << std::setw(10) << "max us" << std::setw(10) << "jit50 us" << std::setw(10) << "jit99 us\n";
    };
    os << "1 kHz servo loop, simulated hand (tick compute; period error)\n";
    header();
    for (const ServoRun& x : r.runs) row(x);
    os << "\nrate ladder\n";
    header();
    for (const ServoRun& x : r.ladder) row(x);
    os << "\nhighest sustained rate (achieved within 1 %, overruns < 0.1 %):\n";
    for (const auto& [scene, hz] : r.sustainableHz) os << "  " << scene << ": " << std::setprecision(0) << hz << " Hz\n";
}

nlohmann::json servoReportJson(const ServoReport& r)
{
    const auto run = [](const ServoRun& x) {
        return nlohmann::json{{"scene", x.scene},           {"rate_hz", x.rateHz},
                              {"achieved_hz", x.achievedHz}, {"seconds", x.seconds},
                              {"ticks", x.ticks},            {"overruns", x.overruns},
                              {"compute_p50_ns", x.computeP50Ns}, {"compute_p99_ns", x.computeP99Ns},
                              {"compute_max_ns", x.computeMaxNs}, {"period_error_p50_ns", x.periodErrP50Ns},
                              {"period_error_p99_ns", x.periodErrP99Ns}};
    };
    nlohmann::json j{{"machine", r.machine}};
    for (const auto& x : r.runs) j["runs"].push_back(run(x));
    for (const auto& x : r.ladder) j["ladder"].push_back(run(x));
    for (const auto& [scene, hz] : r.sustainableHz) j["sustainable_hz"][scene] = hz;
    return j;
}

} // namespace voxhap::bench
