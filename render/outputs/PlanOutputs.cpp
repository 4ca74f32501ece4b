// SPDX-License-Identifier: Apache-2.0
/// @file PlanOutputs.cpp
/// @brief The files a plan leaves: report, markups, views and the predicted
/// force–depth plot, replaced together (PlanOutputs.h).
#include "render/outputs/PlanOutputs.h"

#include "core/AtomicFile.h"
#include "core/Format.h"
#include "planning/Markups.h"
#include "planning/Report.h"
#include "render/outputs/Snapshot.h"
#include "render/plots/ForcePlot.h"
#include "render/raster/ImageFile.h"
#include "render/volume3d/Display.h"

#include <cmath>
#include <future>
#include <optional>

namespace voxhap::render {

namespace fs = std::filesystem;

PlanFiles writePlanOutputs(const planning::Planner& planner, const std::vector<planning::TrajectoryReport>& paths,
    const nlohmann::json& report, const std::string& outDir, bool views, DisplayGuard* early)
{
    PlanFiles f;
    fs::create_directories(outDir);
    const fs::path dir(outDir);
    // Every output replaces an earlier plan's together (OutputSet; docs/reference.md "Reliability"):
    // never a new report beside stale views; an output this plan does not make
    // (no path found, --no-views, no gnuplot) removes the earlier one.
    OutputSet out;
    f.report = (dir / "report.json").string();
    out.add(f.report, [&report](const fs::path& tmp) { planning::writeReport(report, tmp); });

    std::vector<planning::MarkupLine> lines;
    for (std::size_t i = 0; i < paths.size(); ++i)
        lines.push_back({"path " + std::to_string(i + 1), paths[i].entry, paths[i].target});
    f.markups = (dir / "paths.mrk.json").string();
    out.add(f.markups, [&lines](const fs::path& tmp) { planning::writeMarkups(lines, tmp); });

    const std::string png = (dir / "force-depth.png").string();
    const fs::path pngTemporary = temporaryPathFor(png);
    const std::string viewsFile = (dir / "views.png").string();
    // The display first: finishing its start sets $DISPLAY, which must not
    // change while the plot's thread spawns gnuplot with this environment.
    const bool drawViews = views && !paths.empty();
    std::optional<DisplayGuard> display; // the 3D view needs X (Xvfb when there is none)
    DisplayGuard* x = nullptr;
    if (drawViews) {
        if (!early) display.emplace();
        x = early ? early : &*display;
        x->wait();
    }
    // The predicted force–depth profile of the first path, with its tissue bands,
    // drawn (gnuplot may be missing) under the name the set puts in place. gnuplot
    // is a process of its own: it draws while this thread renders the views.
    std::future<bool> plotted;
    std::string plotWhy;
    if (!paths.empty()) {
        ForceTrace trace;
        const auto& best = paths.front();
        trace.title = "path 1: predicted at " + fixed(best.speedMmPerS, 0) + " mm/s (" + planner.scene().name + ")";
        for (const auto& s : best.force) trace.samples.push_back({s.depthMm, s.forceN, s.forceN, 0.0});
        for (const auto& s : best.segments) trace.layers.push_back({s.tissue, s.startMm, s.endMm});
        if (std::isfinite(best.contactMm)) trace.addEvent(best.contactMm, "bone contact");
        plotted = std::async(std::launch::async, [trace = std::move(trace), tmp = pngTemporary.string(), &plotWhy] {
            return plotForceDepth(trace, tmp, plotWhy);
        });
    }
    // Joins the plot's thread (once; later calls do nothing) and records its outcome.
    const auto finishPlot = [&] {
        if (!plotted.valid()) return;
        bool ok = false;
        try {
            ok = plotted.get();
        } catch (const std::exception& e) {
            plotWhy = e.what();
        }
        if (ok) {
            f.plot = png;
        } else {
            f.why = plotWhy;
        }
    };
    // Until the set is committed, a failure joins the plot's thread and removes its temporary.
    try {
        if (drawViews) { // slices through the first target and a 3D view, every path drawn
            RenderRequest req;
            req.views = {ViewKind::Axial, ViewKind::Sagittal, ViewKind::Coronal};
            if (x->available()) {
                // The 3D overview in the fourth quadrant, by the viewer's moving path (a third
                // of the rays per side): a full-quality CPU ray cast of a CT costs seconds,
                // more than the whole plan's budget (docs/reference.md "Planning").
                req.views.push_back(ViewKind::ThreeD);
                req.quality3d = RenderQuality::Moving;
                req.shade3d = false; // an overview beside the slices: no per-voxel normals
                req.criticalSurfaces = false;
                // The paths are the subject: drawn over the body, which from the
                // front lies between the camera and a posterior entry.
                req.linesOnTop3d = true;
            } else {
                f.why3d = x->why();
            }
            req.point = paths.front().target;
            for (std::size_t i = 0; i < lines.size(); ++i) {
                planning::PlannedPath p{lines[i].name, lines[i].entry, lines[i].target, std::nullopt};
                if (const auto& d = paths[i].deflection) { // the predicted bent needle (physics.md §9.6)
                    planning::NeedlePose pose;
                    pose.tip = d->bentShaft.back();
                    pose.direction = (d->bentShaft.back() - d->bentShaft.front()).normalized();
                    pose.lengthMm = planner.scene().needle.lengthMm;
                    pose.shaft = d->bentShaft;
                    p.needle = pose;
                }
                req.plan.paths.push_back(std::move(p));
            }
            Snapshot snap(planner.volume(), req, planner.table());
            std::vector<Image> images;
            for (ViewKind k : snap.views()) images.push_back(snap.render(k));
            f.views = viewsFile;
            out.add(viewsFile, [sheet = contactSheet(images)](const fs::path& tmp) { writePng(sheet, tmp); });
        } else {
            out.remove(viewsFile);
        }
        finishPlot();
        if (!f.plot.empty()) {
            out.add(png, [](const fs::path&) {}); // already at its temporary path
        } else {
            std::error_code ignored;
            fs::remove(pngTemporary, ignored);
            out.remove(png);
        }
        out.commit();
    } catch (...) {
        finishPlot(); // no-op once joined
        std::error_code ignored;
        fs::remove(pngTemporary, ignored);
        throw;
    }
    return f;
}

} // namespace voxhap::render
