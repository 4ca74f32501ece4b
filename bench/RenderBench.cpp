// SPDX-License-Identifier: Apache-2.0
/// @file RenderBench.cpp
#include "bench/RenderBench.h"

#include "bench/SamplerBench.h" // for machineDescription
#include "bench/Stats.h"
#include "render/Display.h"
#include "render/Viewer.h"
#include "core/Errors.h"
#include "volume/phantoms/Phantoms.h"
#include "volume/Volume.h"
#include "volume/VolumeFile.h"

#include <chrono>
#include <cmath>
#include <iomanip>
#include <optional>
#include <sstream>

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
            render::NeedlePose needle;
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

} // namespace

RenderReport runRenderBench(const RenderBenchOptions& o, const Progress& progress)
{
    RenderReport r;
    r.machine = machineDescription();
    render::DisplayGuard display;
    if (!display.available()) throw IoError("bench render: no display for the 3D pane: " + display.why());
    r.display = display.description();
    if (!o.ct.empty()) {
        if (progress) progress(-1.0, "loading " + o.ct);
        const auto t = RenderClock::now();
        const volume::Volume ct = volume::loadVolume(o.ct);
        r.cases.push_back(benchVolume("real CT", ct, renderSecondsSince(t), o, progress));
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
        r.cases.push_back(benchVolume("torso phantom", ph, renderSecondsSince(t), o, progress));
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
    return {{"machine", r.machine}, {"display", r.display}, {"cases", cases}};
}

} // namespace voxhap::bench
