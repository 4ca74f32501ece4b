// SPDX-License-Identifier: Apache-2.0
/// @file CmdView.cpp
/// @brief `voxhap view <volume>`: the interactive planning viewer (four panes,
/// entry and target by clicks, distance and angle tools, a live needle from
/// `voxhap serve --viewer`), or the same driven by a script into a snapshot.

#include "tools/Cli.h"
#include "tools/LoadOptions.h"

#include "core/Errors.h"
#include "haptic/igtl/PoseStream.h"
#include "planning/PlanFile.h"
#include "render/viewer/Viewer.h"
#include "render/viewer/ViewerScript.h"
#include "render/viewer/ViewerWindow.h"
#include "render/volume3d/Display.h"
#include "volume/Volume.h"

#include <nlohmann/json.hpp>

#include <csignal>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>

namespace voxhap::tools {

namespace {

struct ViewOptions {
    CommonOptions common;
    ReaderOptions reader;
    std::string input, plan, save = "plan.json", script, snapshot, size = "1024x1048", mode = "colour", window, point;
    int listen = -1;
    double timeoutS = 0, needleLengthMm = 90.0;
    bool noLabels = false, no3d = false;
};

std::pair<int, int> parseSize(const std::string& text)
{
    const auto x = text.find('x');
    int w = 0, h = 0;
    try {
        std::size_t uw = 0, uh = 0;
        if (x != std::string::npos) {
            w = std::stoi(text.substr(0, x), &uw);
            h = std::stoi(text.substr(x + 1), &uh);
        }
        if (x == std::string::npos || uw != x || uh != text.size() - x - 1) w = h = 0;
    } catch (const std::exception&) {
        w = h = 0;
    }
    if (w < 100 || h < 100 || w > 8192 || h > 8192) {
        throw UsageError("--size: '" + text + "' is not WIDTHxHEIGHT with each side in 100..8192");
    }
    return {w, h};
}

/// Hands the latest streamed pose to the viewer, and says how the stream is doing.
class NeedleFeed {
public:
    NeedleFeed(haptic::PoseReceiver* receiver, double lengthMm) : mReceiver(receiver), mLengthMm(lengthMm) { }
    long poses() const { return mReceiver ? mReceiver->poses() : 0; }
    void pump(render::Viewer& viewer)
    {
        if (!mReceiver) return;
        const long n = mReceiver->poses();
        if (n != mSeen) {
            if (const auto p = mReceiver->latest()) {
                planning::NeedlePose pose;
                pose.tip = p->tip;
                pose.direction = p->direction;
                pose.lengthMm = mLengthMm;
                pose.shaft = p->shaft; // a bending needle's, as streamed; empty: straight
                viewer.setNeedle(pose);
            }
            mSeen = n;
        }
        std::ostringstream note;
        note << "needle stream :" << mReceiver->port() << (mReceiver->connected() ? " connected, " : " waiting, ") << n
             << " poses";
        viewer.setNote(note.str());
    }

private:
    haptic::PoseReceiver* mReceiver;
    double mLengthMm;
    long mSeen = 0;
};

nlohmann::json paneJson(const render::Viewer& v)
{
    nlohmann::json panes = nlohmann::json::array();
    for (const render::PaneRect& p : v.layout().panes) {
        const render::ViewFrame& f = v.frame(p.view);
        const render::Vec2d o = v.imageOrigin(p.view);
        panes.push_back({{"view", render::viewName(p.view)}, {"pane", {p.x, p.y, p.width, p.height}},
            {"image_origin", {int(o.x()), int(o.y())}}, {"image_size", {f.width, f.height}}, {"pixel_mm", f.pixelMm}});
    }
    return panes;
}

int run(const ViewOptions& o)
{
    // Cheap inputs first: a bad size, plan or script fails before the volume loads.
    const auto [width, height] = parseSize(o.size);
    render::ViewerOptions vo;
    vo.width = width, vo.height = height;
    try {
        vo.mode = render::parseBlendMode(o.mode);
        if (!o.window.empty()) vo.window = render::parseWindow(o.window);
    } catch (const ValueError& e) {
        throw UsageError(e.what());
    }
    if (!o.point.empty()) vo.point = parseVec3(o.point, "--point");
    if (o.listen > 65535) throw UsageError("--listen: port " + std::to_string(o.listen) + " outside 0..65535");
    vo.labels = !o.noLabels;
    vo.planOut = o.save;
    if (!o.plan.empty()) vo.plan = planning::loadPlan(o.plan);
    render::ScriptPlayer script(
        o.script.empty() ? std::vector<render::ScriptStep>{} : render::loadViewerScript(o.script), o.script,
        o.listen >= 0);
    const volume::TissueTable& table = tissueTable(o.common);
    const bool windowed = o.snapshot.empty();
    if (windowed) {
        const char* d = std::getenv("DISPLAY");
        if (!d || !render::displayReachable(d)) {
            throw IoError(
                "view: no X display ($DISPLAY unset or not answering); for a headless run give --snapshot FILE");
        }
    }
    // Before any thread starts: the guard may set $DISPLAY for this process.
    std::optional<render::DisplayGuard> display;
    if (!o.no3d) display.emplace();
    vo.threeD = display && display->available();
    vo.threeDNote = o.no3d ? "off (--no-3d)" : display->why();

    std::unique_ptr<haptic::PoseReceiver> receiver;
    if (o.listen >= 0) {
        receiver = std::make_unique<haptic::PoseReceiver>(o.listen);
        std::cerr << "voxhap view: listening for needle poses (OpenIGTLink TRANSFORM) on 127.0.0.1:" << receiver->port()
                  << '\n';
    }
    NeedleFeed feed(receiver.get(), o.needleLengthMm);

    const volume::Volume v = loadVolumeWithProgress(o.input, o.reader, stderrIsTerminal() && !o.common.json);
    checkViewOptions(v, o.window, vo.point);
    render::Viewer viewer(v, vo, table);

    const InterruptGuard guard;
    render::ViewerRunHooks hooks;
    hooks.pump = [&feed](render::Viewer& shown) {
        feed.pump(shown);
        return feed.poses();
    };
    hooks.stop = [] { return InterruptGuard::interrupted(); };
    hooks.timeoutS = o.timeoutS;
    render::ViewerRunEnd end;
    if (windowed) {
        render::ViewerWindow win(width, height, "voxhap view: " + o.input);
        end = render::runInWindow(viewer, win, script, hooks);
    } else {
        end = render::runToSnapshot(viewer, script, hooks, o.snapshot);
    }
    const long frames = end.frames;
    std::string why = end.why;
    if (InterruptGuard::interrupted()) why = "interrupted";

    if (o.common.json) {
        nlohmann::json j;
        j["input"] = o.input;
        j["window"] = {width, height};
        j["panes"] = paneJson(viewer);
        j["point_mm"] = {viewer.point().x(), viewer.point().y(), viewer.point().z()};
        j["frames"] = frames;
        j["poses"] = feed.poses();
        j["ended"] = why;
        j["snapshot"] = o.snapshot.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.snapshot);
        j["status"] = viewer.status();
        std::cout << j.dump(2) << '\n';
    } else {
        std::cout << "view   " << o.input << ": " << width << " x " << height << " px, " << std::fixed
                  << std::setprecision(3) << viewer.frame(render::ViewKind::Axial).pixelMm << " mm pixels, " << frames
                  << " frames, ended: " << why << '\n';
        if (receiver) std::cout << "needle " << feed.poses() << " poses received\n";
        if (!o.snapshot.empty()) std::cout << "wrote  " << o.snapshot << '\n';
        std::cout << "status " << viewer.status() << '\n';
    }
    return 0;
}

} // namespace

Action registerView(CLI::App& app)
{
    auto o = std::make_shared<ViewOptions>();
    CLI::App* cmd = app.add_subcommand("view",
        "Interactive viewer: axial, sagittal, coronal and 3D panes; click the entry and target, measure "
        "distances and angles; show a live needle streamed by `voxhap serve --viewer`");
    cmd->footer(
        "Keys: n navigate (click moves the slices), p plan (click entry, then target), d distance, a angle\n"
        "(two segments), arrows or wheel: slices, w window preset, c clear, s save the plan, q quit.\n"
        "3D pane: drag rotates (200 degrees across the pane), wheel zooms (1.21x a step), r resets the camera;\n"
        "while it moves the pane is drawn at reduced quality, at full quality once the drag ends or\n"
        "0.3 s after the last wheel step.\n"
        "Views are radiological: axial from the feet, coronal from the front (patient's left on the right).");
    cmd->add_option("volume", o->input, "A volume: .vdb, .nrrd, .nii, .mha or a DICOM folder")->required();
    cmd->add_option("--plan", o->plan, "Paths to show: plan.json (voxhap-plan/1) or a 3D Slicer .mrk.json line")
        ->check(CLI::ExistingFile);
    cmd->add_option("--save", o->save, "Where key s saves the plan (default plan.json)");
    cmd->add_option("--script", o->script,
           "Play events from a file (key, click, scroll, drag, release, wait-pose, sleep; one a line)")
        ->check(CLI::ExistingFile);
    cmd->add_option("--snapshot", o->snapshot, "No window: play the script, write the window as this PNG and exit");
    cmd->add_option("--listen", o->listen,
           "Receive the live needle (OpenIGTLink TRANSFORM; a bending needle's shaft as the POINT "
           "'voxhap-shaft' before it) on 127.0.0.1:PORT (0: any free port)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--timeout", o->timeoutS, "Quit after this many seconds")->check(CLI::PositiveNumber);
    cmd->add_option(
           "--needle-length", o->needleLengthMm, "Length of the streamed needle drawn behind its tip [mm] (default 90)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--size", o->size, "Window WIDTHxHEIGHT [px] (default 1024x1048)");
    cmd->add_option("--mode", o->mode, "3D blend mode: colour, grey, mip or sum (default colour)");
    cmd->add_option("--window", o->window,
        "Slice window: bone, soft, lung or WIDTH,LEVEL in HU on CT (default soft); on MR WIDTH,LEVEL in its units, "
        "default the 1st to 99th percentile of the body's voxels");
    cmd->add_option(
        "--point", o->point, "First crosshair x,y,z [mm, LPS] (default: the plan's target, else the centre)");
    cmd->add_flag("--no-labels", o->noLabels, "Slices without the tissue colours");
    cmd->add_flag("--no-3d", o->no3d, "No 3D pane (no GL needed)");
    addReaderOptions(*cmd, o->reader);
    addCommonOptions(*cmd, o->common);
    return [o] { return run(*o); };
}

} // namespace voxhap::tools
