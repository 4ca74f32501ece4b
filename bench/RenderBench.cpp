// SPDX-License-Identifier: Apache-2.0
/// @file RenderBench.cpp
#include "bench/RenderBench.h"

#include "bench/SamplerBench.h" // for machineDescription
#include "bench/Stats.h"
#include "core/Errors.h"
#include "phantoms/Phantoms.h"
#include "render/viewer/OrbitCamera.h"
#include "render/viewer/Viewer.h"
#include "render/views/RenderVolume.h"
#include "render/volume3d/Display.h"
#include "render/volume3d/VolumeView3d.h"
#include "volume/Volume.h"
#include "volume/VolumeFile.h"

#include <chrono>
#include <cmath>
#include <ctime>
#include <iomanip>
#include <optional>
#include <sstream>
#include <tuple>
#include <utility>

namespace voxhap::bench {

namespace {

using RenderClock = std::chrono::steady_clock;

double renderSecondsSince(RenderClock::time_point t)
{
    return std::chrono::duration<double>(RenderClock::now() - t).count();
}

Seconds renderStat(const std::vector<double>& x)
{
    const SampleStats st = sampleStats(x);
    return {st.mean, st.sd, st.n};
}

RenderCase benchVolume(const std::string& name, const volume::Volume& v, double loadS, const RenderBenchOptions& o,
    const Progress& progress)
{
    const auto& table = volume::TissueTable::builtin();
    RenderCase c;
    c.name = name;
    const auto box = v.indexBox();
    const auto dim = box.dims();
    c.dims = std::to_string(dim.x()) + " x " + std::to_string(dim.y()) + " x " + std::to_string(dim.z());
    c.loadS = loadS;
    render::ViewerOptions vo;
    vo.width = o.width, vo.height = o.height;
    std::vector<double> setup, first, steady, slices;
    render::Image firstImage;
    for (int i = 0; i < o.firstFrames; ++i) {
        if (progress)
            progress(-1.0, name + ": first frame " + std::to_string(i + 1) + " of " + std::to_string(o.firstFrames));
        auto t = RenderClock::now();
        render::Viewer viewer(v, vo, table);
        setup.push_back(renderSecondsSince(t));
        t = RenderClock::now();
        render::Image img = viewer.render();
        first.push_back(renderSecondsSince(t));
        if (i + 1 < o.firstFrames) continue;
        // The last viewer goes on: steady frames (all four panes), then the slices
        // alone, interleaved so that both see the same machine load.
        firstImage = std::move(img);
        for (int k = 0; k < o.steadyFrames; ++k) {
            if (progress)
                progress(
                    -1.0, name + ": steady frame " + std::to_string(k + 1) + " of " + std::to_string(o.steadyFrames));
            viewer.invalidate();
            t = RenderClock::now();
            render::Image again = viewer.render();
            steady.push_back(renderSecondsSince(t));
            if (k == 0) {
                for (int y = 0; y < again.height(); ++y) {
                    for (int x = 0; x < again.width(); ++x)
                        c.differingPixels += !(again.at(x, y) == firstImage.at(x, y));
                }
            }
            // A streamed needle pose: the slices' overlays and the 3D pane's lines
            // are redrawn over cached pictures; no volume rendering.
            planning::NeedlePose needle;
            needle.tip = viewer.point() + Vec3d(0, 0, double(k));
            needle.direction = Vec3d(0, 0.6, -0.8);
            viewer.setNeedle(needle);
            t = RenderClock::now();
            viewer.render();
            slices.push_back(renderSecondsSince(t));
        }
    }
    c.setup = renderStat(setup);
    c.first = renderStat(first);
    c.steady = renderStat(steady);
    c.slices = renderStat(slices);
    std::vector<double> ratios;
    for (std::size_t k = 0; k < steady.size(); ++k) ratios.push_back(steady[k] / std::max(1e-12, slices[k]));
    c.steadyOverSlices = renderStat(ratios).mean;
    return c;
}

/// A 3D frame of exactly @p w × @p h pixels from the front, the volume's box fitted inside.
render::ViewFrame orbitFrame(const render::WorldBounds& box, int w, int h)
{
    const Vec3d ext = box.max - box.min;
    const double pixel = std::max(std::abs(ext.x()) / w, std::abs(ext.z()) / h);
    render::ViewFrame f = render::viewFrame(render::ViewKind::ThreeD, box, 0.5 * (box.min + box.max), pixel, 1 << 20);
    const Vec3d c = f.centre();
    f.width = w, f.height = h;
    f.origin = c - f.pixelMm * (0.5 * (w - 1) * f.right + 0.5 * (h - 1) * f.down);
    return f;
}

/// CPU seconds of the whole process (every thread): on a shared machine the wall
/// time depends on the load, this does not.
double processCpuSeconds() { return double(std::clock()) / CLOCKS_PER_SEC; }

double meanGreyDifference(const render::Image& a, const render::Image& b)
{
    double s = 0;
    for (int y = 0; y < a.height(); ++y) {
        for (int x = 0; x < a.width(); ++x) {
            const render::Rgb p = a.at(x, y), q = b.at(x, y);
            s += std::abs((p.r + p.g + p.b) - (q.r + q.g + q.b)) / 3.0;
        }
    }
    return s / std::max(1.0, double(a.width()) * a.height());
}

double quantile(std::vector<double> x, double q)
{
    if (x.empty()) return 0;
    std::sort(x.begin(), x.end());
    const double at = q * double(x.size() - 1);
    const std::size_t i = std::size_t(at);
    const double t = at - double(i);
    return i + 1 < x.size() ? (1 - t) * x[i] + t * x[i + 1] : x[i];
}

/// Median wall and process-CPU seconds of @p frames full-quality frames of @p view.
std::pair<double, double> medianFullFrame(render::VolumeView3d& view, int frames)
{
    std::vector<double> wall, cpu;
    for (int i = 0; i < frames; ++i) {
        const double c0 = processCpuSeconds();
        const auto t = RenderClock::now();
        view.render(render::RenderQuality::Full);
        wall.push_back(renderSecondsSince(t));
        cpu.push_back(processCpuSeconds() - c0);
    }
    return {sampleStats(wall).median, sampleStats(cpu).median};
}

struct MovingCandidate {
    render::MovingPath path;
    int factor;
    std::string name;
};

std::vector<OrbitCase> orbitVolume(
    const std::string& name, const volume::Volume& v, const RenderBenchOptions& o, const Progress& progress)
{
    const auto& table = volume::TissueTable::builtin();
    const render::RenderVolume rv(v, true); // as the viewer: labels for the critical surfaces when there are any
    const render::ViewFrame home = orbitFrame(rv.worldBounds(), o.orbitWidth, o.orbitHeight);
    const render::ViewerOptions defaults;
    // The viewer's default first, then the other candidates.
    const std::vector<MovingCandidate> candidates{{render::MovingPath::Subsample, 3, "subsample x3"},
        {render::MovingPath::Subsample, 4, "subsample x4"}, {render::MovingPath::Subsample, 2, "subsample x2"},
        {render::MovingPath::Shrunk, 2, "shrunk x2"}, {render::MovingPath::AutoRate, 1, "auto rate 10/s"}};
    std::vector<OrbitCase> out;
    for (const MovingCandidate& cand : candidates) {
        if (progress) progress(-1.0, name + ": orbit, " + cand.name);
        OrbitCase c;
        c.volume = name;
        c.path = cand.name;
        c.chosen = cand.path == defaults.moving && cand.factor == defaults.movingFactor;
        render::View3dStyle style;
        style.moving = cand.path;
        style.movingFactor = cand.factor;
        style.sampleVoxels = defaults.sampleVoxels; // the viewer's full-quality step
        style.window = rv.defaultWindow(style.mode);
        render::Overlays none;
        none.letters = false, none.scaleBar = false;
        auto owned = std::make_unique<render::VolumeView3d>(rv, home, style, table, none);
        render::VolumeView3d& view = *owned;
        auto t = RenderClock::now();
        const render::Image fullHome = view.render(render::RenderQuality::Full);
        c.firstFullS = renderSecondsSince(t);
        c.trianglesFull = view.criticalTriangles();
        t = RenderClock::now();
        const render::Image movingHome = view.render(render::RenderQuality::Moving);
        c.firstMovingS = renderSecondsSince(t);
        c.trianglesMoving = view.criticalTriangles();
        c.movingVsFullGrey = meanGreyDifference(movingHome, fullHome);
        std::tie(c.fullS, c.cpuFullS) = medianFullFrame(view, o.fullFrames);
        // The orbit: azimuth steps while the button is held, each frame at moving quality.
        render::OrbitCamera camera(home);
        std::vector<double> moving, fps, cpuMoving;
        for (int i = 0; i < o.orbitFrames; ++i) {
            camera.azimuth(360.0 / o.orbitFrames);
            const double cpu = processCpuSeconds();
            t = RenderClock::now();
            view.setCamera(camera.frame());
            view.render(render::RenderQuality::Moving);
            moving.push_back(renderSecondsSince(t));
            cpuMoving.push_back(processCpuSeconds() - cpu);
            fps.push_back(1.0 / std::max(1e-9, moving.back()));
        }
        c.frames = int(moving.size());
        c.fpsMedian = quantile(fps, 0.5);
        c.fpsP10 = quantile(fps, 0.1);
        c.cpuMovingS = quantile(cpuMoving, 0.5);
        // Released: the viewer's next frame is at full quality, at the last camera.
        t = RenderClock::now();
        view.render(render::RenderQuality::Full);
        c.stopToFullS = renderSecondsSince(t);
        c.fullOverMoving = c.fullS / std::max(1e-12, quantile(moving, 0.5));
        if (c.chosen) {
            // Full-quality candidates: the same view at other ray steps, each against
            // the one-voxel frame of the same camera (the reference, listed first).
            // One view (one GL context) at a time: the orbit's is closed first.
            owned.reset();
            render::Image oneVoxel;
            for (const double step : {1.0, 1.5, 1.75, 2.0}) {
                render::View3dStyle other = style;
                other.sampleVoxels = step;
                render::VolumeView3d stepView(rv, home, other, table, none);
                const render::Image first = stepView.render(render::RenderQuality::Full);
                if (step == 1.0) {
                    oneVoxel = first;
                    c.viewerVsOneVoxelGrey = meanGreyDifference(fullHome, oneVoxel);
                }
                FullStep fs;
                fs.stepVoxels = step;
                fs.greyVsOneVoxel = meanGreyDifference(first, oneVoxel);
                std::tie(fs.fullS, fs.cpuFullS) = medianFullFrame(stepView, o.fullFrames);
                c.fullSteps.push_back(fs);
            }
        }
        if (progress) {
            std::ostringstream line;
            line << name << ", " << cand.name << ": " << std::fixed << std::setprecision(1) << c.fpsMedian
                 << " fps median, " << c.fpsP10 << " p10; full " << std::setprecision(3) << c.fullS
                 << " s; stop to full " << c.stopToFullS << " s; cpu s/frame moving " << c.cpuMovingS << ", full "
                 << c.cpuFullS;
            progress(-1.0, line.str());
        }
        out.push_back(c);
    }
    return out;
}

} // namespace

RenderReport runRenderBench(const RenderBenchOptions& o, const Progress& progress)
{
    RenderReport r;
    r.machine = machineDescription();
    r.orbitWidth = o.orbitWidth, r.orbitHeight = o.orbitHeight;
    render::DisplayGuard display;
    if (!display.available()) throw IoError("bench render: no display for the 3D pane: " + display.why());
    r.display = display.description();
    if (!o.ct.empty()) {
        if (progress) progress(-1.0, "loading " + o.ct);
        const auto t = RenderClock::now();
        const volume::Volume ct = volume::loadVolume(o.ct);
        const double loadS = renderSecondsSince(t);
        if (o.fourView) r.cases.push_back(benchVolume("real CT", ct, loadS, o, progress));
        if (o.orbitFrames > 0) {
            for (OrbitCase& c : orbitVolume("real CT", ct, o, progress)) r.orbits.push_back(std::move(c));
        }
    }
    {
        if (progress) progress(-1.0, "torso phantom " + std::to_string(o.phantomSide) + "^3");
        const auto& table = volume::TissueTable::builtin();
        volume::TorsoParams tp;
        const volume::PhantomModel model = volume::torsoModel(tp, table);
        const Vec3d ext = model.bounds.max - model.bounds.min;
        tp.grid.spacing = ext / double(o.phantomSide); // anisotropic, like a CT: o.phantomSide voxels per side
        const auto t = RenderClock::now();
        const volume::Volume ph = volume::makePhantom(model, tp.grid, table);
        const double loadS = renderSecondsSince(t);
        if (o.fourView) r.cases.push_back(benchVolume("torso phantom", ph, loadS, o, progress));
        if (o.orbitFrames > 0) {
            for (OrbitCase& c : orbitVolume("torso phantom", ph, o, progress)) r.orbits.push_back(std::move(c));
        }
    }
    if (progress) progress(-1.0, "");
    return r;
}

void printRenderReport(std::ostream& os, const RenderReport& r)
{
    os << "machine: " << r.machine << "\ndisplay: " << r.display << "\n\n";
    os << "four-view frame of `voxhap view` (1024 x 1048 window unless set): mean ± sd [s]\n";
    os << std::left << std::setw(16) << "volume" << std::setw(20) << "voxels" << std::setw(18) << "viewer setup"
       << std::setw(18) << "first frame" << std::setw(18) << "steady frame" << std::setw(18) << "needle moved"
       << "steady/needle\n";
    const auto s = [](const Seconds& x) {
        std::ostringstream t;
        t << std::fixed << std::setprecision(3) << x.mean << " ± " << x.sd;
        return t.str();
    };
    for (const RenderCase& c : r.cases) {
        os << std::left << std::setw(16) << c.name << std::setw(20) << c.dims << std::setw(18) << s(c.setup)
           << std::setw(18) << s(c.first) << std::setw(18) << s(c.steady) << std::setw(18) << s(c.slices) << std::fixed
           << std::setprecision(1) << c.steadyOverSlices << "x\n";
    }
    os << "\nfirst frames n = " << (r.cases.empty() ? 0 : r.cases[0].first.n)
       << " (fresh viewers), steady n = " << (r.cases.empty() ? 0 : r.cases[0].steady.n)
       << "; steady/needle is the mean of per-round ratios in this run;\n"
          "a needle-moved frame redraws the slices and the overlays over the cached 3D picture.\n";
    for (const RenderCase& c : r.cases) {
        os << c.name << ": loaded in " << std::setprecision(2) << c.loadS
           << " s; steady frame differs from the first in " << c.differingPixels << " pixels\n";
    }
    if (r.orbits.empty()) return;
    os << "\ninteractive 3D view, " << r.orbitWidth << " x " << r.orbitHeight
       << ", colour mode: a scripted orbit (azimuth steps) at moving quality, then the full-quality frame\n";
    os << std::left << std::setw(16) << "volume" << std::setw(18) << "moving path" << std::setw(12) << "fps med"
       << std::setw(12) << "fps p10" << std::setw(12) << "full [s]" << std::setw(14) << "stop->full" << std::setw(12)
       << "full/moving" << std::setw(12) << "|dgrey|"
       << "first full, first moving [s]\n";
    for (const OrbitCase& c : r.orbits) {
        os << std::left << std::setw(16) << c.volume << std::setw(18) << (c.path + (c.chosen ? " *" : "")) << std::fixed
           << std::setprecision(1) << std::setw(12) << c.fpsMedian << std::setw(12) << c.fpsP10 << std::setprecision(3)
           << std::setw(12) << c.fullS << std::setw(14) << c.stopToFullS << std::setprecision(1) << std::setw(12)
           << c.fullOverMoving << std::setw(12) << c.movingVsFullGrey << std::setprecision(2) << c.firstFullS << ", "
           << c.firstMovingS << "\n";
    }
    os << "* the viewer's moving path. fps over " << r.orbits.front().frames
       << " moving frames; stop->full: the drag released at the end of the orbit to the full-quality frame\n"
          "(a wheel zoom adds the viewer's 0.3 s settle time); |dgrey|: mean grey difference, moving against full,\n"
          "at the home camera; cpu s/frame: process CPU time (all threads), which the machine's load does not\n"
          "inflate. Targets: fps >= 10 while moving, full quality <= 1.5 s after.\n";
    for (const OrbitCase& c : r.orbits) {
        if (c.chosen && c.trianglesFull > 0) {
            os << "critical surfaces, " << c.volume << ": " << c.trianglesFull << " triangles at full quality, "
               << c.trianglesMoving << " while moving (" << c.path << ")\n";
        }
    }
    os << "\nfull-quality ray step (the viewer's uses " << render::ViewerOptions{}.sampleVoxels
       << " voxels; |dgrey| against one-voxel steps at the home camera):\n"
       << std::left << std::setw(16) << "volume" << std::setw(14) << "step [voxel]" << std::setw(12) << "full [s]"
       << std::setw(16) << "cpu s/frame"
       << "|dgrey| vs 1 voxel\n";
    for (const OrbitCase& c : r.orbits) {
        if (!c.chosen) continue;
        os << std::left << std::setw(16) << c.volume << std::setw(14) << "viewer's" << std::fixed
           << std::setprecision(3) << std::setw(12) << c.fullS << std::setw(16) << c.cpuFullS << std::setprecision(2)
           << c.viewerVsOneVoxelGrey << "\n";
        for (const FullStep& f : c.fullSteps) {
            os << std::left << std::setw(16) << c.volume << std::setprecision(2) << std::setw(14) << f.stepVoxels
               << std::setprecision(3) << std::setw(12) << f.fullS << std::setw(16) << f.cpuFullS
               << std::setprecision(2) << f.greyVsOneVoxel << "\n";
        }
    }
}

nlohmann::json renderReportJson(const RenderReport& r)
{
    const auto s = [](const Seconds& x) { return nlohmann::json{{"mean_s", x.mean}, {"sd_s", x.sd}, {"n", x.n}}; };
    nlohmann::json cases = nlohmann::json::array();
    for (const RenderCase& c : r.cases) {
        cases.push_back({{"volume", c.name}, {"voxels", c.dims}, {"load_s", c.loadS}, {"setup", s(c.setup)},
            {"first_frame", s(c.first)}, {"steady_frame", s(c.steady)}, {"needle_frame", s(c.slices)},
            {"steady_over_needle", c.steadyOverSlices}, {"differing_pixels", c.differingPixels}});
    }
    nlohmann::json orbits = nlohmann::json::array();
    for (const OrbitCase& c : r.orbits) {
        orbits.push_back(
            {{"volume", c.volume}, {"moving_path", c.path}, {"chosen", c.chosen}, {"fps_median", c.fpsMedian},
                {"fps_p10", c.fpsP10}, {"full_frame_s", c.fullS}, {"stop_to_full_s", c.stopToFullS},
                {"full_over_moving", c.fullOverMoving}, {"moving_vs_full_mean_grey", c.movingVsFullGrey},
                {"first_full_s", c.firstFullS}, {"first_moving_s", c.firstMovingS}, {"frames", c.frames},
                {"critical_triangles_full", c.trianglesFull}, {"critical_triangles_moving", c.trianglesMoving}});
        nlohmann::json steps = nlohmann::json::array();
        for (const FullStep& f : c.fullSteps) {
            steps.push_back({{"step_voxels", f.stepVoxels}, {"full_frame_s", f.fullS}, {"cpu_full_s", f.cpuFullS},
                {"mean_grey_vs_one_voxel", f.greyVsOneVoxel}});
        }
        if (!steps.empty()) {
            orbits.back()["full_steps"] = steps;
            orbits.back()["viewer_full_vs_one_voxel_mean_grey"] = c.viewerVsOneVoxelGrey;
        }
    }
    return {{"machine", r.machine}, {"display", r.display}, {"cases", cases},
        {"orbit",
            {{"width", r.orbitWidth}, {"height", r.orbitHeight},
                {"targets", {{"fps_min", 10.0}, {"stop_to_full_max_s", 1.5}}}, {"cases", orbits}}}};
}

} // namespace voxhap::bench
