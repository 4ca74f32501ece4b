// SPDX-License-Identifier: Apache-2.0
/// @file CmdBench.cpp
/// @brief `voxhap bench sampler`: the runtime-versus-error table of shaft integration.

#include "tools/Cli.h"

#include "bench/RenderBench.h"
#include "bench/SamplerBench.h"
#include "bench/ServoBench.h"
#include "core/AtomicFile.h"

#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>

namespace voxhap::tools {

namespace {

struct BenchOptions {
    bench::SamplerBenchOptions sampler;
    bench::ServoBenchOptions servo;
    bench::RenderBenchOptions render;
    bool quick = false;
    bool noVtk = false;
    bool fidelityGiven = false;
    bool noRealtime = false;
    std::string json, png;
    std::vector<CLI::Option*> jsonOptions; ///< each subcommand's --json
    /// `--json` given without a file: JSON on stdout instead of the table.
    bool jsonStdout() const
    {
        for (const CLI::Option* opt : jsonOptions)
            if (opt->count() > 0 && json.empty()) return true;
        return false;
    }
};

/// A progress line on a terminal, overwritten in place; nothing otherwise.
Progress progressLine()
{
    const bool tty = stderrIsTerminal();
    return [tty](double, std::string_view stage) {
        if (tty) std::cerr << "\r\033[K" << stage << std::flush;
    };
}

/// The figures out: `--json` alone prints them as JSON on stdout instead of the table,
/// as every command's --json does; `--json FILE` keeps the table and also writes the
/// JSON to FILE (benchmarks.md: results compared across commits).
void emit(const BenchOptions& o, const nlohmann::json& j, const std::function<void(std::ostream&)>& table)
{
    if (o.jsonStdout()) {
        std::cout << j.dump(2) << '\n';
        return;
    }
    table(std::cout);
    if (o.json.empty()) return;
    writeStreamAtomically(o.json, [&](std::ostream& out) { out << j.dump(2) << '\n'; });
    std::cout << "json: " << o.json << '\n';
}

int runSampler(BenchOptions o)
{
    if (o.quick) {
        o.sampler.paths = 12;
        o.sampler.depths = 20;
        o.sampler.repetitions = 2;
        if (!o.fidelityGiven) o.sampler.fidelityPaths = 1000;
    }
    o.sampler.vtk = !o.noVtk;
    if (!o.sampler.ctDir.empty()) o.sampler.workloads.push_back("ct");
    if (!o.sampler.mrDir.empty()) o.sampler.workloads.push_back("mr");
    const auto progress = progressLine();
    const auto report = bench::runSamplerBench(o.sampler, progress);
    progress(-1.0, "");
    emit(o, bench::samplerReportJson(report), [&](std::ostream& os) { bench::printSamplerReport(os, report); });
    if (!o.png.empty()) {
        std::string why;
        if (!bench::plotSamplerReport(report, o.png, why)) throw std::runtime_error(o.png + ": " + why);
        (o.jsonStdout() ? std::cerr : std::cout) << "plot: " << o.png << '\n';
    }
    return 0;
}

int runServo(BenchOptions o)
{
    o.servo.realtime = !o.noRealtime;
    if (o.quick) {
        o.servo.seconds = 5.0;
        o.servo.ladderSeconds = 1.0;
        o.servo.igtlSeconds = 3.0;
        o.servo.floorSeconds = 2.0;
    }
    const auto progress = progressLine();
    const auto report = bench::runServoBench(o.servo, progress);
    progress(-1.0, "");
    emit(o, bench::servoReportJson(report), [&](std::ostream& os) { bench::printServoReport(os, report); });
    return 0;
}

int runRender(BenchOptions o)
{
    if (o.quick) o.render.firstFrames = 1, o.render.steadyFrames = 2, o.render.orbitFrames = 12;
    const auto progress = progressLine();
    const auto report = bench::runRenderBench(o.render, progress);
    progress(-1.0, "");
    emit(o, bench::renderReportJson(report), [&](std::ostream& os) { bench::printRenderReport(os, report); });
    return 0;
}

/// `--json` (JSON on stdout instead of the table) or `--json FILE` (the table, and the
/// JSON also written to FILE).
void addJsonOption(CLI::App& cmd, BenchOptions& o)
{
    o.jsonOptions.push_back(cmd.add_option("--json", o.json,
                                   "Print the figures as JSON on stdout instead of the table; with FILE, print the "
                                   "table and also write the JSON to FILE")
                                ->expected(0, 1));
}

} // namespace

Action registerBench(CLI::App& app)
{
    auto o = std::make_shared<BenchOptions>();
    CLI::App* cmd = app.add_subcommand("bench", "Measure speed against error (docs: benchmarks.md)");
    cmd->require_subcommand(1);
    CLI::App* sampler = cmd->add_subcommand("sampler",
        "Shaft integration: every strategy and step against closed forms, with dense-array and VTK baselines");
    sampler->footer("Workloads: the R1 layered slab (closed form) and the torso phantom, 0.5 mm voxels; shafts up to\n"
                    "100 mm tilted 0-60 degrees. With --ct and --mr also a real CT (segmented, damping per label)\n"
                    "and a T1-weighted MR (damping from T1 voxel by voxel), shafts from the skin along random\n"
                    "directions through the body. Ratios are measured in one run, configurations interleaved;\n"
                    "the peer row is a two-level OpenVDB block DDA on the same grids and segments, and both\n"
                    "sums are checked against a plane-crossing sum in long double (no walk).");
    sampler->add_flag("--quick", o->quick, "Fewer paths, depths and rounds (seconds instead of a minute)");
    sampler->add_option("--paths", o->sampler.paths, "Shaft directions per workload (default 48)")
        ->check(CLI::Range(1, 10000));
    sampler->add_option("--depths", o->sampler.depths, "Insertion depths per path (default 40)")
        ->check(CLI::Range(1, 10000));
    sampler->add_option("--repetitions", o->sampler.repetitions, "Interleaved rounds (default 5)")
        ->check(CLI::Range(1, 1000));
    sampler->add_option("--speed", o->sampler.speedMmPerS, "Insertion speed for force errors, mm/s (default 10)")
        ->check(CLI::Range(0.001, 10000.0));
    sampler->add_option("--spacing", o->sampler.spacingMm, "Phantom voxel size, mm (default 0.5)")
        ->check(CLI::Range(0.1, 5.0));
    sampler->add_flag("--no-vtk", o->noVtk, "Skip the (slow) vtkProbeFilter baseline");
    sampler
        ->add_option("--fidelity-paths", o->sampler.fidelityPaths,
            "Random paths per workload for the path-based error statistics (default 10000, 1000 with --quick; 0: none)")
        ->check(CLI::Range(0, 1000000))
        ->each([o](const std::string&) { o->fidelityGiven = true; });
    sampler->add_option("--ct", o->sampler.ctDir, "Add the real-CT workload: a DICOM folder or volume file")
        ->check(CLI::ExistingPath);
    sampler->add_option("--mr", o->sampler.mrDir, "Add the real-MR workload: a T1-weighted DICOM folder or volume file")
        ->check(CLI::ExistingPath);
    addJsonOption(*sampler, *o);
    sampler->add_option("--png", o->png, "Also draw time against error, log-log (needs gnuplot)");
    CLI::App* servo = cmd->add_subcommand(
        "servo", "The servo loop in real time with the simulated hand: tick compute, jitter, overruns, sustained rate");
    servo->footer(
        "Scenes senac-average (labels, lock, LOR) and kyung (voxel damping, pivot, bone). A 1 kHz run, then a\n"
        "rate ladder 1-100 kHz; periods up to 100 us are spun, not slept.");
    servo->add_option("--seconds", o->servo.seconds, "Length of the 1 kHz run (default 30)")
        ->check(CLI::Range(0.5, 3600.0));
    servo->add_flag("--quick", o->quick, "5 s at 1 kHz and 1 s per ladder rate");
    servo
        ->add_option("--load", o->servo.load,
            "Run N CPU-bound processes (a busy loop each, normal priority) beside the loop (default 0)")
        ->check(CLI::Range(0, 64));
    servo->add_option("--repeats", o->servo.repeats, "1 kHz runs per scene; their median is reported (default 1)")
        ->check(CLI::Range(1, 100));
    servo
        ->add_option("--ladder-repeats", o->servo.ladderRepeats,
            "Full rate ladders per scene; the highest sustained rate is their median (default 1)")
        ->check(CLI::Range(1, 20));
    servo
        ->add_option("--catch-up", o->servo.catchUpPeriods,
            "Missed periods the loop runs late instead of dropping (ServoOptions::catchUpPeriods; default -1: those "
            "within the watchdog's 20 ms; 0: drop every missed period)")
        ->check(CLI::Range(0, 1000));
    servo->add_flag(
        "--no-align", [o](std::int64_t) { o->servo.align = false; },
        "Do not align spinning loops' grids to the machine's interruption phase (ServoOptions::alignToInterruptions)");
    servo->add_option("--pin", o->servo.pinCpu, "Pin the loop thread to this CPU (default: not pinned)")
        ->check(CLI::Range(0, 1023));
    servo
        ->add_option("--floor-seconds", o->servo.floorSeconds,
            "Length of the interruption probe, a real-time thread that only reads the clock (default 10, 0: none)")
        ->check(CLI::Range(0.0, 3600.0));
    servo->add_option("--scenes", o->servo.scenes,
        "Scenes to run (default senac-average kyung kyung-bending lumbar-puncture lumbar-puncture-bending)");
    servo
        ->add_option(
            "--rates", o->servo.rates, "The rate ladder [Hz] (default 1000 2000 5000 10000 20000 50000 100000)")
        ->check(CLI::Range(1.0, 1e6));
    servo->add_flag("--no-realtime", o->noRealtime,
        "Do not ask for real-time scheduling (SCHED_FIFO) and locked memory for the loop");
    addJsonOption(*servo, *o);
    CLI::App* render = cmd->add_subcommand("render",
        "Four-view frame of the viewer, first and steady, and the interactive 3D orbit (moving fps, full quality after "
        "stopping), on a CT (--ct) and a 256^3 torso phantom");
    render->add_option("--ct", o->render.ct, "A CT: DICOM folder or volume file (default: the phantom only)")
        ->check(CLI::ExistingPath);
    render->add_option("--first", o->render.firstFrames, "Fresh viewers timed on their first frame (default 2)")
        ->check(CLI::Range(1, 100));
    render->add_option("--steady", o->render.steadyFrames, "Steady frames per volume (default 5)")
        ->check(CLI::Range(1, 1000));
    render
        ->add_option("--orbit-frames", o->render.orbitFrames,
            "Moving frames of the 3D orbit per moving path, 512x375 (default 36; 0: no orbit)")
        ->check(CLI::Range(0, 10000));
    render->add_flag_function(
        "--orbit-only", [o](std::int64_t) { o->render.fourView = false; },
        "Only the interactive 3D orbit, not the four-view frames");
    render->add_flag("--quick", o->quick, "One first frame, two steady frames, a 12-frame orbit");
    addJsonOption(*render, *o);
    return [o, servo, render] {
        return servo->parsed() ? runServo(*o) : render->parsed() ? runRender(*o) : runSampler(*o);
    };
}

} // namespace voxhap::tools
