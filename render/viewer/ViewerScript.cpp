// SPDX-License-Identifier: Apache-2.0
/// @file ViewerScript.cpp
#include "render/viewer/ViewerScript.h"

#include "core/BoundedRead.h"

#include "core/Errors.h"
#include "render/raster/ImageFile.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <thread>

namespace voxhap::render {

namespace {

constexpr double kScriptMaxWaitS = 600.0; // a script that waits longer is a mistake, not a test

ViewKind scriptPane(const std::string& name, const std::string& where)
{
    for (ViewKind k : {ViewKind::Axial, ViewKind::Sagittal, ViewKind::Coronal, ViewKind::ThreeD}) {
        if (name == viewName(k)) return k;
    }
    throw ValueError(where + "unknown pane '" + name + "' (expected axial, sagittal, coronal or 3d)");
}

double scriptNumber(std::istringstream& in, const std::string& what, const std::string& where)
{
    std::string tok;
    if (!(in >> tok)) throw ValueError(where + "missing " + what);
    std::size_t used = 0;
    double v = 0;
    try {
        v = std::stod(tok, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used != tok.size() || !std::isfinite(v)) throw ValueError(where + what + " '" + tok + "' is not a number");
    return v;
}

} // namespace

std::vector<ScriptStep> parseViewerScript(std::string_view text, const std::string& origin)
{
    std::vector<ScriptStep> steps;
    std::istringstream lines{std::string(text)};
    std::string line;
    int n = 0;
    while (std::getline(lines, line)) {
        ++n;
        if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
        std::istringstream in(line);
        std::string verb;
        if (!(in >> verb)) continue;
        const std::string where = origin + ":" + std::to_string(n) + ": ";
        ScriptStep s;
        s.line = n;
        if (verb == "key") {
            s.event.kind = ViewerEvent::Kind::Key;
            if (!(in >> s.event.key)) throw ValueError(where + "key: missing the key name");
        } else if (verb == "click") {
            std::string pane;
            if (!(in >> pane)) throw ValueError(where + "click: missing the pane");
            s.event.kind = ViewerEvent::Kind::Click;
            s.event.pane = scriptPane(pane, where);
            const double x = scriptNumber(in, "x", where), y = scriptNumber(in, "y", where);
            s.event.px = Vec2d(x, y);
        } else if (verb == "scroll") {
            std::string pane;
            if (!(in >> pane)) throw ValueError(where + "scroll: missing the pane");
            s.event.kind = ViewerEvent::Kind::Scroll;
            s.event.pane = scriptPane(pane, where);
            const double count = scriptNumber(in, "steps", where);
            if (count != std::round(count) || std::abs(count) > 1e6)
                throw ValueError(where + "scroll: steps must be an integer");
            s.event.steps = int(count);
        } else if (verb == "drag") {
            std::string pane;
            if (!(in >> pane)) throw ValueError(where + "drag: missing the pane");
            s.event.kind = ViewerEvent::Kind::Drag;
            s.event.pane = scriptPane(pane, where);
            const double dx = scriptNumber(in, "dx", where), dy = scriptNumber(in, "dy", where);
            s.event.px = Vec2d(dx, dy);
        } else if (verb == "release") {
            s.event.kind = ViewerEvent::Kind::Release;
            s.event.pane = ViewKind::ThreeD;
        } else if (verb == "wait-pose" || verb == "sleep") {
            s.kind = verb == "sleep" ? ScriptStep::Kind::Sleep : ScriptStep::Kind::WaitPose;
            s.seconds = scriptNumber(in, "seconds", where);
            if (!(s.seconds >= 0.0 && s.seconds <= kScriptMaxWaitS)) {
                throw ValueError(where + verb + ": seconds must be in 0..600");
            }
        } else {
            throw ValueError(
                where + "unknown step '" + verb + "' (expected key, click, scroll, drag, release, wait-pose or sleep)");
        }
        std::string extra;
        if (in >> extra) throw ValueError(where + "unexpected '" + extra + "' after the " + verb + " step");
        steps.push_back(std::move(s));
    }
    return steps;
}

std::vector<ScriptStep> loadViewerScript(const std::filesystem::path& file)
{
    // A regular file within the 16 MiB limit of text inputs: not a FIFO, /dev/zero or a huge file.
    return parseViewerScript(readBoundedFile(file, "viewer script"), file.string());
}

ScriptPlayer::ScriptPlayer(std::vector<ScriptStep> steps, std::string origin, bool listening)
    : mSteps(std::move(steps)), mOrigin(std::move(origin)), mListening(listening)
{
}

bool ScriptPlayer::advance(Viewer& viewer, long poses, Clock::time_point now)
{
    while (!done()) {
        const ScriptStep& s = mSteps[mNext];
        if (s.kind == ScriptStep::Kind::Event) {
            ++mNext;
            if (!viewer.handle(s.event)) return false;
            continue;
        }
        if (!mWaitStarted) {
            mWaitStarted = now;
            mPosesAtStart = poses;
        }
        const double waited = std::chrono::duration<double>(now - *mWaitStarted).count();
        const bool finished = s.kind == ScriptStep::Kind::Sleep ? waited >= s.seconds : poses > mPosesAtStart;
        if (!finished && s.kind == ScriptStep::Kind::WaitPose && waited >= s.seconds) {
            throw IoError(mOrigin + ":" + std::to_string(s.line) + ": wait-pose: no needle pose within " +
                std::to_string(s.seconds) + " s" + (poses == 0 && !mListening ? " (no --listen)" : ""));
        }
        if (!finished) return true;
        mWaitStarted.reset();
        ++mNext;
    }
    return true;
}

bool deliver(Viewer& viewer, const WindowInput& in)
{
    switch (in.kind) {
    case WindowInput::Kind::Click:
        return viewer.clickWindow(in.x, in.y);
    case WindowInput::Kind::Scroll:
        viewer.scrollWindow(in.x, in.y, in.steps);
        return true;
    case WindowInput::Kind::Motion:
        viewer.dragWindow(in.x, in.y);
        return true;
    case WindowInput::Kind::Release:
        viewer.releaseWindow();
        return true;
    case WindowInput::Kind::Key: {
        ViewerEvent e;
        e.kind = ViewerEvent::Kind::Key;
        e.key = in.key;
        return viewer.handle(e);
    }
    case WindowInput::Kind::Close:
        return false;
    }
    return true;
}

namespace {

double secondsSince(std::chrono::steady_clock::time_point t)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

} // namespace

ViewerRunEnd runInWindow(Viewer& viewer, ViewerWindow& window, ScriptPlayer& script, const ViewerRunHooks& hooks)
{
    const auto start = std::chrono::steady_clock::now();
    ViewerRunEnd end{0, "quit"};
    bool running = true;
    while (running && !hooks.stop()) {
        for (const WindowInput& in : window.poll(viewer.dirty() ? 0 : 15)) running = deliver(viewer, in) && running;
        const long poses = hooks.pump(viewer);
        viewer.settle(); // full quality once the 3D camera has stopped
        if (window.mapped() && !script.done()) running = script.advance(viewer, poses) && running;
        if (hooks.timeoutS > 0 && secondsSince(start) >= hooks.timeoutS) {
            end.why = "timeout";
            break;
        }
        if (viewer.dirty()) {
            window.show(viewer.render());
            ++end.frames;
        }
    }
    return end;
}

ViewerRunEnd runToSnapshot(
    Viewer& viewer, ScriptPlayer& script, const ViewerRunHooks& hooks, const std::filesystem::path& png)
{
    const auto start = std::chrono::steady_clock::now();
    ViewerRunEnd end{0, "script done"};
    long poses = hooks.pump(viewer);
    bool running = true;
    while (running && !script.done() && !hooks.stop()) {
        running = script.advance(viewer, poses);
        poses = hooks.pump(viewer);
        if (running && !script.done()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
        if (hooks.timeoutS > 0 && secondsSince(start) >= hooks.timeoutS) {
            end.why = "timeout";
            break;
        }
    }
    hooks.pump(viewer);
    viewer.settle(std::chrono::steady_clock::time_point::max()); // the snapshot at full quality
    // A window shows a failed save in its status bar; a headless run fails on it.
    if (!viewer.saveError().empty()) throw IoError(viewer.saveError());
    writePng(viewer.render(), png);
    ++end.frames;
    return end;
}

} // namespace voxhap::render
