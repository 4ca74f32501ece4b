// SPDX-License-Identifier: Apache-2.0
/// @file CmdServe.cpp
/// @brief `voxhap serve`: the servo loop in real time against a device, with a live
/// status line; Ctrl-C stops cleanly and writes the session and the metrics.

#include "tools/Cli.h"
#include "tools/Guide.h"

#include "assessment/Metrics.h"

#include "core/AtomicFile.h"
#include "core/Errors.h"
#include "haptic/devices/DeviceSpec.h"
#include "haptic/igtl/IgtlDevice.h"
#include "haptic/igtl/PoseStream.h"
#include "haptic/scene/Scene.h"
#include "haptic/servo/ServoLoop.h"
#include "haptic/servo/Session.h"

#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <thread>

namespace voxhap::tools {

namespace {

namespace fs = std::filesystem;

struct ServeOptions {
    CommonOptions common;
    std::string scene, device = "hand", out = "voxhap-serve", viewer;
    double speed = 0, duration = 0, rate = 0;
    bool reckless = false;
    GuideOptions guide;
};

/// What --device names, checked (and a replay's file read) before anything is
/// loaded: a typo in it is reported at once, not after the scene's volume was built.
haptic::DeviceSpec deviceSpec(const std::string& text)
{
    try {
        return haptic::parseDeviceSpec(text);
    } catch (const ValueError& e) {
        throw UsageError("--" + std::string(e.what())); // "--device 'x' is not hand, sim, ..."
    }
}

std::string layerName(const haptic::NeedleForceModel& m, int i)
{
    return i >= 0 && i < int(m.layers().size()) ? m.layers()[std::size_t(i)].name : "outside";
}

int run(const ServeOptions& o, const CLI::App& cmd)
{
    // Ctrl-C from the start, set-up included: an interrupt while the scene
    // loads still ends in a clean stop with the (empty) session written.
    const InterruptGuard guard;
    const haptic::DeviceSpec spec = deviceSpec(o.device); // before any loading: a typo is said at once
    const volume::TissueTable& table = tissueTable(o.common);
    const std::optional<haptic::GuideLine> guide = guideLine(o.guide, cmd); // a bad plan file fails first
    haptic::Scene scene = loadSceneSayingDefaults(o.scene);
    if (cmd.count("--rate")) scene.rateHz = o.rate;
    const haptic::SceneInstance inst(scene, nullptr, table);
    auto model = inst.makeModel(guide);
    // The simulated hand has no end of its own: a minute unless --duration says.
    const double duration = o.duration > 0.0 ? o.duration : spec.kind == "hand" ? 60.0 : 0.0;
    haptic::DeviceContext context = haptic::deviceContext(
        *model, cmd.count("--speed") ? o.speed : scene.speedMmPerS, scene.approachMm, scene.depthMm);
    context.careful = !o.reckless;
    context.announce = [](const std::string& line) { std::cerr << "voxhap serve: " << line << '\n'; };
    auto device = haptic::makeDevice(spec, context);
    haptic::ServoOptions so;
    so.rateHz = scene.rateHz;
    so.realtime = true; // SCHED_FIFO and locked memory when allowed; one line below when not
    haptic::ServoLoop loop(*model, *device, so);
    // The live needle for `voxhap view --listen`: sent from this (status) thread,
    // never the servo thread, at about 50 Hz (a display rate).
    std::unique_ptr<haptic::PoseSender> viewer;
    if (!o.viewer.empty()) {
        std::string host;
        int port = 0;
        try {
            haptic::parseHostPort(o.viewer, "--viewer", host, port);
        } catch (const ValueError& e) {
            throw UsageError(e.what());
        }
        viewer = std::make_unique<haptic::PoseSender>(host, port);
    }
    long sentRecords = 0;

    // The session goes to disk as it runs (bounded memory at any rate and length);
    // it replaces an earlier one in the output folder only when it is complete.
    haptic::SessionRecorder session(o.out, model->layers(), model->path().direction, scene.success, inst.target());
    const bool live = stderrIsTerminal() && !o.common.json;
    const auto t0 = std::chrono::steady_clock::now();
    const auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
    if (!InterruptGuard::interrupted()) {
        loop.start();
        if (!loop.realtimeStatus().why.empty()) std::cerr << "voxhap serve: " << loop.realtimeStatus().why << '\n';
        // One line when stderr is not a terminal (a script, a test harness):
        // from here on Ctrl-C stops the loop and writes the session.
        if (!live) std::cerr << "voxhap serve: running (Ctrl-C stops and writes the session)\n" << std::flush;
    }
    while (!InterruptGuard::interrupted() && loop.running() && (duration <= 0.0 || elapsed() < duration)) {
        std::this_thread::sleep_for(std::chrono::milliseconds(viewer ? 20 : 100));
        session.drain(loop);
        if (viewer && session.recordCount() > sentRecords) {
            sentRecords = session.recordCount();
            haptic::StreamedPose pose{session.lastRecord()->tip, session.lastRecord()->direction, {}};
            loop.shaft().read(pose.shaft); // a bending needle's shaft; empty: straight
            viewer->send(pose);
        }
        if (live) {
            std::cerr << "\r" << std::fixed << std::setprecision(1) << elapsed() << " s  " << std::setprecision(0)
                      << double(loop.ticks()) / std::max(elapsed(), 1e-9) << " Hz  tick p99 " << std::setprecision(1)
                      << loop.stats().computeQuantileNs(0.99) * 1e-3 << " us  F " << std::setprecision(2)
                      << loop.lastForceN() << " N  " << layerName(*model, loop.lastLayer()) << "  events "
                      << session.eventCount() << "        " << std::flush;
        }
    }
    // The hand may still hold the device: the force ramps to zero at the watchdog's
    // rate and a zero force is sent before anything is written.
    loop.releaseAndStop();
    session.drain(loop);
    if (live) std::cerr << '\n';
    const double wall = elapsed();

    const haptic::TraineeMetrics m = session.metrics();
    // The trainee metrics under the names `voxhap assess` reads (assessment/Metrics.h), then the run's own.
    nlohmann::json j = assessment::traineeMetricsJson(m);
    j.update({{"scene", scene.name}, {"device", device->name()}, {"ticks", loop.ticks()},
        {"rate_hz", double(loop.ticks()) / std::max(wall, 1e-9)},
        {"tick_compute_ns",
            {{"p50", loop.stats().computeQuantileNs(0.5)}, {"p99", loop.stats().computeQuantileNs(0.99)},
                {"max", loop.maxComputeNs()}}},
        {"period_error_ns_p99", loop.stats().jitterQuantileNs(0.99)}, {"overruns", loop.overruns()},
        {"skipped_periods", loop.skippedPeriods()}, {"records", session.recordCount()},
        {"dropped_records", loop.droppedRecords()}, {"dropped_events", loop.droppedEvents()},
        {"interrupted", InterruptGuard::interrupted()}});
    if (const haptic::Guidance* g = model->guidance()) {
        const auto point = [](const Vec3d& p) { return nlohmann::json::array({p.x(), p.y(), p.z()}); };
        j["guidance"] = {{"file", o.guide.file}, {"path", guide ? nlohmann::json(o.guide.path) : nlohmann::json()},
            {"entry", point(g->line().entry)}, {"target", point(g->line().target)},
            {"stiffness_N_per_mm", g->params().stiffnessNPerMm}, {"max_force_N", g->params().maxForceN}};
    }
    if (model->palpation()) j["palpation"] = true;
    // The session and its metrics replace an earlier run's together (OutputSet): never a new
    // session.csv beside a stale metrics.json.
    OutputSet outputs;
    session.finish(outputs, loop.droppedRecords());
    outputs.addStream(fs::path(o.out) / "metrics.json", [&j](std::ostream& out) { out << j.dump(2) << '\n'; });
    outputs.commit();
    if (o.common.json) {
        std::cout << j.dump(2) << '\n';
        return 0;
    }
    std::cout << "voxhap serve: " << scene.name << ", device " << device->name() << ", " << loop.ticks() << " ticks in "
              << std::fixed << std::setprecision(1) << wall << " s"
              << (InterruptGuard::interrupted() ? " (interrupted)" : "") << "\n"
              << (model->guidance() ? "  guidance        toward " +
                             (guide ? guideDescription(o.guide, *guide) : std::string("the scene's path")) + "\n"
                                    : std::string())
              << (model->palpation() ? "  palpation       on\n" : "")

              << "  success         " << (m.success ? "yes" : "no") << " (" << haptic::successRuleName(m.outcome.rule)
              << "): " << m.outcome.reason << "\n"
              << "  dura            " << (m.duraIntact ? "intact" : "punctured") << "\n"
              << "  pops            " << m.pops << ", bone contacts " << m.boneContacts << "\n"
              << "  force limited   "
              << (m.forceLimits > 0 ? std::to_string(m.forceLimits) + " times by the device's peak or I²t limit"
                                    : std::string("never"))
              << "\n"
              << "  speed           " << std::setprecision(2) << m.speedMeanMmPerS << " mm/s mean, variance "
              << m.speedVarianceMm2PerS2 << " mm²/s²\n";
    if (m.overshootMm) std::cout << "  epidural travel " << *m.overshootMm << " mm\n";
    std::cout << "  tick compute    p50 " << std::setprecision(1) << loop.stats().computeQuantileNs(0.5) * 1e-3
              << " us, p99 " << loop.stats().computeQuantileNs(0.99) * 1e-3 << " us, overruns " << loop.overruns()
              << ", periods skipped " << loop.skippedPeriods() << "\n"
              << "\noutputs:\n  " << (fs::path(o.out) / "session.csv").string() << "\n  "
              << (fs::path(o.out) / "events.csv").string() << "\n  " << (fs::path(o.out) / "metrics.json").string()
              << '\n';
    return 0;
}

} // namespace

Action registerServe(CLI::App& app)
{
    // The devices of libraries that add kinds, by their explicit call (DeviceSpec.h says why).
    haptic::registerIgtlDevice();
    auto o = std::make_shared<ServeOptions>();
    std::string names; // the palpation scenes among them: the back felt before the needle
    for (const auto& n : haptic::builtinSceneNames()) names += (names.empty() ? "" : ", ") + n;
    CLI::App* cmd = app.add_subcommand("serve",
        "Run the haptic servo loop in real time against a device; Ctrl-C stops "
        "and writes the session and trainee metrics");
    cmd->add_option("--scene", o->scene, "Scene: a JSON file or a built-in name (" + names + ")")->required();
    cmd->add_option("--device", o->device,
        "hand (a simulated trainee's hand, default), sim (a scripted constant-speed insertion), "
        "igtl[:PORT] (an OpenIGTLink server on loopback, default port 18944) or replay:FILE (a recorded "
        "session.csv)");
    cmd->add_option("--speed", o->speed, "Hand or script speed [mm/s] (default: the scene's)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--duration", o->duration, "Stop after this many seconds (hand default 60)")
        ->check(CLI::PositiveNumber);
    cmd->add_flag("--reckless", o->reckless, "The simulated hand does not stop when it feels the loss of resistance");
    cmd->add_option("--rate", o->rate, "Servo rate [Hz] (default: the scene's, 1000)")->check(CLI::Range(1.0, 1e6));
    cmd->add_option("--out,-o", o->out, "Output directory (default voxhap-serve)");
    cmd->add_option("--viewer", o->viewer,
        "Stream the needle pose at about 50 Hz to `voxhap view --listen PORT` at [HOST:]PORT (OpenIGTLink "
        "TRANSFORM; a bending needle's shaft as the POINT 'voxhap-shaft' before it)");
    addGuideOptions(*cmd, o->guide);
    addCommonOptions(*cmd, o->common);
    return [o, cmd] { return run(*o, *cmd); };
}

} // namespace voxhap::tools
