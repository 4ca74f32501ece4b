// SPDX-License-Identifier: Apache-2.0
/// @file CmdRender.cpp
/// @brief `voxhap render <volume>`: axial, sagittal, coronal and 3D snapshots
/// as PNGs, with paths, crosshair, scale bar and orientation letters, plus a
/// contact sheet. Slices need no display; the 3D view uses $DISPLAY or an
/// Xvfb started for the run, and says so on stderr.

#include "tools/Cli.h"
#include "tools/LoadOptions.h"

#include "core/Errors.h"
#include "planning/PlanFile.h"
#include "registration/Resample.h"
#include "render/outputs/Snapshot.h"
#include "render/raster/ImageFile.h"
#include "render/slices/FusionViews.h"
#include "render/views/RenderVolume.h"
#include "render/volume3d/Display.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>

namespace voxhap::tools {

namespace {

namespace fs = std::filesystem;

struct RenderOptions {
    CommonOptions common;
    ReaderOptions reader;
    std::string input, views = "axial,sagittal,coronal,3d", mode = "colour", caster = "auto", window, path, point,
                       out = "voxhap-render";
    double pixelMm = 0.0;
    int size = 768;
    bool noLabels = false, noSurfaces = false;
    bool fusion = false;
    std::string fusionMr;
};

render::RenderRequest request(const RenderOptions& o)
{
    render::RenderRequest r;
    try {
        r.views = render::parseViews(o.views);
        r.mode = render::parseBlendMode(o.mode);
        if (!o.window.empty()) r.window = render::parseWindow(o.window);
    } catch (const ValueError& e) {
        throw UsageError(e.what());
    }
    r.caster = o.caster == "gpu" ? render::RayCaster::Gpu
        : o.caster == "cpu"      ? render::RayCaster::Cpu
                                 : render::RayCaster::Auto;
    if (r.caster == render::RayCaster::Cpu && r.mode == render::BlendMode::Sum) {
        throw UsageError("--caster cpu: the CPU ray caster has no summed projection");
    }
    if (!o.point.empty()) r.point = parseVec3(o.point, "--point");
    r.pixelMm = o.pixelMm;
    r.maxPixels = o.size;
    r.labels = !o.noLabels;
    r.criticalSurfaces = !o.noSurfaces;
    return r;
}

double secondsSince(std::chrono::steady_clock::time_point t)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

/// `--fusion`: the registration checked by eye, in the three planes, against the
/// MR at its header geometry (the MR file the fused volume recorded, or --fusion-mr).
int runFusion(const RenderOptions& o)
{
    const volume::Volume fused = loadVolumeWithProgress(o.input, o.reader, stderrIsTerminal() && !o.common.json);
    const auto& record = fused.metadata().fusion;
    if (!record) throw IoError(o.input + ": not a fused volume (no registration record): make one with voxhap fuse");
    ReaderOptions mrReader;
    mrReader.series = record->mrSeries;
    mrReader.volume = std::size_t(record->mrVolume);
    const std::string mrPath = o.fusionMr.empty() ? record->mrPath : o.fusionMr;
    const volume::Volume mr = loadVolumeWithProgress(mrPath, mrReader, stderrIsTerminal() && !o.common.json);
    const volume::Channel c = fused.has(volume::Channel::T1) ? volume::Channel::T1 : volume::Channel::Intensity;
    const volume::Channel mc = mr.has(volume::Channel::T1) ? volume::Channel::T1 : volume::Channel::Intensity;
    volume::Volume before(fused.transformPtr()->copy(), fused.indexBox());
    before.setGrid(c, registration::resampleOnto(fused, mr, mc, registration::AffineMap{}));
    const auto b = fused.worldBounds();
    const Vec3d point = o.point.empty() ? Vec3d(0.5 * (b[0] + b[1])) : parseVec3(o.point, "--point");
    render::FusionViewStyle style;
    style.pixelMm = o.pixelMm;
    style.maxPixels = std::min(o.size, 512);
    fs::create_directories(o.out);
    nlohmann::json files = nlohmann::json::array();
    for (render::ViewKind k : {render::ViewKind::Axial, render::ViewKind::Sagittal, render::ViewKind::Coronal}) {
        const std::string name = std::string(render::viewName(k));
        const fs::path file = fs::path(o.out) / ("fusion-" + name + ".png");
        render::writePng(render::fusionSheet(render::renderFusionPanels(fused, before, k, point, style),
                             render::renderFusionPanels(fused, fused, k, point, style), render::sliceTitle(k, point)),
            file);
        files.push_back(file.string());
    }
    if (o.common.json) {
        std::cout << nlohmann::json{{"input", o.input}, {"mr", mrPath}, {"views", files}}.dump(2) << '\n';
    } else {
        for (const auto& f : files)
            std::cout << "wrote  " << f.get<std::string>() << "  (header geometry above, registered below)\n";
    }
    return 0;
}

int run(const RenderOptions& o)
{
    if (o.fusion) return runFusion(o);
    render::RenderRequest req = request(o);
    // Cheap inputs first: a bad plan fails before the volume loads.
    if (!o.path.empty()) req.plan = planning::loadPlan(o.path);
    const volume::TissueTable& table = tissueTable(o.common);
    const bool threeD = std::find(req.views.begin(), req.views.end(), render::ViewKind::ThreeD) != req.views.end();
    // Before any thread starts: the guard may set $DISPLAY for this process.
    std::optional<render::DisplayGuard> display;
    if (threeD) display.emplace();

    const auto start = std::chrono::steady_clock::now();
    const volume::Volume v = loadVolumeWithProgress(o.input, o.reader, stderrIsTerminal() && !o.common.json);
    const double loadS = secondsSince(start);
    checkViewOptions(v, o.window, req.point);
    const auto setUp = std::chrono::steady_clock::now();
    render::Snapshot snap(v, req, table);
    const double setUpS = secondsSince(setUp);

    fs::create_directories(o.out);
    std::vector<render::Image> images;
    nlohmann::json files = nlohmann::json::array();
    std::string failure;
    for (render::ViewKind k : snap.views()) {
        if (k == render::ViewKind::ThreeD && !display->available()) {
            failure = "3d view: " + display->why() + "; the slices were written";
            continue;
        }
        const auto t = std::chrono::steady_clock::now();
        render::Image img = snap.render(k);
        const double s = secondsSince(t);
        const std::string name = k == render::ViewKind::ThreeD
            ? "3d-" + std::string(render::blendModeName(req.mode)) + ".png"
            : std::string(render::viewName(k)) + ".png";
        render::writePng(img, fs::path(o.out) / name);
        files.push_back({{"view", render::viewName(k)}, {"file", (fs::path(o.out) / name).string()},
            {"width", img.width()}, {"height", img.height()}, {"seconds", s}});
        images.push_back(std::move(img));
    }
    const fs::path sheet = fs::path(o.out) / "sheet.png";
    if (!images.empty()) render::writePng(render::contactSheet(images), sheet);

    const Vec3d p = snap.point();
    if (o.common.json) {
        nlohmann::json j;
        j["input"] = o.input;
        j["views"] = files;
        j["sheet"] = sheet.string();
        j["point_mm"] = {p.x(), p.y(), p.z()};
        j["display"] = !display ? "none needed" : display->description();
        j["load_seconds"] = loadS;
        j["setup_seconds"] = setUpS;
        j["dense_bytes"] = snap.volume().denseBytes();
        std::cout << j.dump(2) << '\n';
    } else {
        std::cout << std::fixed << std::setprecision(3) << "read   " << o.input << " in " << loadS
                  << " s; handed to VTK in " << setUpS << " s (" << snap.volume().denseBytes() / (1 << 20) << " MiB)\n"
                  << std::setprecision(1) << "point  " << p.x() << ", " << p.y() << ", " << p.z() << " mm (LPS)\n";
        for (const auto& f : files) {
            std::cout << "wrote  " << f["file"].get<std::string>() << "  " << f["width"] << " x " << f["height"] << ", "
                      << std::setprecision(3) << f["seconds"].get<double>() << " s\n";
        }
        if (!images.empty()) std::cout << "wrote  " << sheet.string() << "  (contact sheet)\n";
    }
    // Which path the views took, on stderr (one line): slices never need GL.
    if (display && display->available())
        std::cerr << "voxhap render: slices without GL; " << display->description() << '\n';
    if (!failure.empty()) throw IoError(failure);
    return 0;
}

} // namespace

Action registerRender(CLI::App& app)
{
    auto o = std::make_shared<RenderOptions>();
    CLI::App* cmd = app.add_subcommand("render",
        "Snapshots of a volume: axial, sagittal, coronal and 3D views with paths, as PNGs and a contact sheet");
    cmd->add_option("volume", o->input, "A volume: .vdb, .nrrd, .nii, .mha or a DICOM folder")->required();
    cmd->add_option("--views", o->views, "Comma-separated views: axial, sagittal, coronal, 3d (default all four)");
    cmd->add_option("--mode", o->mode, "3D blend mode: colour (tissue colours), grey, mip or sum (default colour)");
    cmd->add_option("--caster", o->caster, "3D ray caster: auto (the faster for the mode), gpu or cpu")
        ->check(CLI::IsMember({"auto", "gpu", "cpu"}));
    cmd->add_option("--window", o->window,
        "Window: bone, soft, lung or WIDTH,LEVEL in HU on CT (default soft; MIP: bone); on MR WIDTH,LEVEL in its "
        "units, default the 1st to 99th percentile of the body's voxels");
    cmd->add_option("--path", o->path, "Planned paths: plan.json (voxhap-plan/1) or a 3D Slicer .mrk.json line")
        ->check(CLI::ExistingFile);
    cmd->add_option("--point", o->point,
        "Slice position and crosshair x,y,z [mm, LPS] (default: the path's target, else the centre)");
    cmd->add_option("--pixel", o->pixelMm, "Pixel size [mm] (default: the finest voxel size)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--size", o->size, "Largest side of a view [px] (default 768)")->check(CLI::Range(32, 4096));
    cmd->add_flag("--no-labels", o->noLabels, "Slices without the tissue colours");
    cmd->add_flag("--no-surfaces", o->noSurfaces, "3D view without the critical-structure surfaces");
    cmd->add_flag("--fusion", o->fusion,
        "A fused volume (voxhap fuse): checkerboard, CT bone edges over the MR, and the MR in colour over the CT, in "
        "the three planes, registered and at the header geometry (fusion-axial.png, ...)");
    cmd->add_option(
        "--fusion-mr", o->fusionMr, "With --fusion: the MR file (default: the one the fused volume recorded)");
    cmd->add_option("--out,-o", o->out, "Output directory (default voxhap-render)");
    addReaderOptions(*cmd, o->reader);
    addCommonOptions(*cmd, o->common);
    return [o] { return run(*o); };
}

} // namespace voxhap::tools
