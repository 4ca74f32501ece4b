// SPDX-License-Identifier: Apache-2.0
/// @file VolumeView3d.cpp
/// @brief The VTK pipeline of the 3D view (vtkGPUVolumeRayCastMapper: under
/// Xvfb, Mesa's llvmpipe runs all four blend modes).
#include "render/volume3d/VolumeView3d.h"

#include "core/Errors.h"
#include "render/detail/VtkVolume.h"
#include "render/volume3d/Display.h"
#include "volume/TissueTable.h"

#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkColorTransferFunction.h>
#include <vtkDiscreteFlyingEdges3D.h>
#include <vtkFixedPointVolumeRayCastMapper.h>
#include <vtkGPUVolumeRayCastMapper.h>
#include <vtkImageShrink3D.h>
#include <vtkLookupTable.h>
#include <vtkPiecewiseFunction.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkUnsignedCharArray.h>
#include <vtkVolume.h>
#include <vtkVolumeProperty.h>
#include <vtkWindowToImageFilter.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <map>
#include <optional>

namespace voxhap::render {

namespace {

/// Opacity per millimetre in the composite modes, by kind of tissue [chosen]:
/// bone dominates, critical organs show through soft tissue, and 300 mm of soft
/// tissue still let a third of the light through (exp(−300 · 0.004) ≈ 0.3).
constexpr double kBoneOpacity = 0.3;
constexpr double kCriticalOpacity = 0.05;
constexpr double kSoftOpacity = 0.004;
/// The critical surfaces of a full-quality frame: the volume shows through them [chosen].
constexpr double kSurfaceOpacity = 0.6;
/// Grey mode: bone is what lies above this CT number [HU].
constexpr double kBoneHu = 1000.0;
/// Tissue whose typical CT number is below this is air-like (lung): transparent [HU].
constexpr double kAirLikeHu = -400.0;
/// The summed projection maps a ray through the whole depth of average tissue to this grey.
constexpr double kSumDepthGrey = 0.8;

void colourTransfer(const volume::TissueTable& table, const RenderVolume::Impl& v, vtkColorTransferFunction* colour,
    vtkPiecewiseFunction* opacity)
{
    // One control point per tissue at its typical CT number; tissues sharing a
    // number keep the first (bone before soft tissue, as the table lists them).
    std::map<double, const volume::Tissue*> byHu;
    for (const volume::Tissue& t : table.tissues()) {
        if (t.id != 0) byHu.emplace(t.huTypical, &t);
    }
    opacity->AddPoint(v.lo, 0.0);
    opacity->AddPoint(std::max(v.lo, v.background) + 1.0, 0.0);
    for (const auto& [hu, t] : byHu) {
        colour->AddRGBPoint(hu, t->colour[0] / 255.0, t->colour[1] / 255.0, t->colour[2] / 255.0);
        const double a = hu < kAirLikeHu ? 0.0
            : t->rigid                   ? kBoneOpacity
            : t->critical                ? kCriticalOpacity
                                         : kSoftOpacity;
        opacity->AddPoint(hu, a);
    }
}

void greyRamp(const WindowLevel& w, vtkColorTransferFunction* colour)
{
    colour->AddRGBPoint(w.level - 0.5 * w.width, 0.0, 0.0, 0.0);
    colour->AddRGBPoint(w.level + 0.5 * w.width, 1.0, 1.0, 1.0);
}

vtkSmartPointer<vtkActor> lineActor(const std::vector<std::pair<Vec3d, Vec3d>>& segments, Rgb colour, double widthPx)
{
    auto points = vtkSmartPointer<vtkPoints>::New();
    auto lines = vtkSmartPointer<vtkCellArray>::New();
    for (const auto& [a, b] : segments) {
        const vtkIdType ids[2] = {points->InsertNextPoint(a.data()), points->InsertNextPoint(b.data())};
        lines->InsertNextCell(2, ids);
    }
    auto poly = vtkSmartPointer<vtkPolyData>::New();
    poly->SetPoints(points);
    poly->SetLines(lines);
    auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    mapper->SetInputData(poly);
    auto actor = vtkSmartPointer<vtkActor>::New();
    actor->SetMapper(mapper);
    actor->GetProperty()->SetColor(colour.r / 255.0, colour.g / 255.0, colour.b / 255.0);
    actor->GetProperty()->SetLineWidth(float(widthPx));
    actor->GetProperty()->SetLighting(false);
    return actor;
}

vtkSmartPointer<vtkActor> pointActor(const std::vector<Vec3d>& pts, Rgb colour, double sizePx)
{
    auto points = vtkSmartPointer<vtkPoints>::New();
    auto verts = vtkSmartPointer<vtkCellArray>::New();
    for (const Vec3d& p : pts) {
        const vtkIdType id = points->InsertNextPoint(p.data());
        verts->InsertNextCell(1, &id);
    }
    auto poly = vtkSmartPointer<vtkPolyData>::New();
    poly->SetPoints(points);
    poly->SetVerts(verts);
    auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    mapper->SetInputData(poly);
    auto actor = vtkSmartPointer<vtkActor>::New();
    actor->SetMapper(mapper);
    actor->GetProperty()->SetColor(colour.r / 255.0, colour.g / 255.0, colour.b / 255.0);
    actor->GetProperty()->SetPointSize(float(sizePx));
    actor->GetProperty()->SetRenderPointsAsSpheres(true);
    return actor;
}

/// Per-axis shrink factors that make a voxel about @p widthMm wide on every
/// axis: an anisotropic CT (0.7 × 0.7 × 2.5 mm) is reduced in-plane only.
std::array<int, 3> shrinkFactors(double widthMm, const Vec3d& spacing)
{
    std::array<int, 3> f{};
    for (int a = 0; a < 3; ++a) f[a] = std::max(1, int(std::lround(widthMm / spacing[a])));
    return f;
}

/// The surfaces of the table's critical tissues in @p labels (one pass of
/// discrete flying edges for all of them), coloured by tissue, at @p opacity;
/// null if the table marks none.
vtkSmartPointer<vtkActor> criticalSurfaceActor(
    vtkImageData* labels, const volume::TissueTable& table, vtkMatrix4x4* dataToWorld, double opacity)
{
    auto surfaces = vtkSmartPointer<vtkDiscreteFlyingEdges3D>::New();
    surfaces->SetInputData(labels);
    int n = 0;
    auto lut = vtkSmartPointer<vtkLookupTable>::New();
    lut->SetNumberOfTableValues(table.maxId() + 1);
    lut->SetTableRange(-0.5, table.maxId() + 0.5);
    lut->Build();
    for (const volume::Tissue& t : table.tissues()) {
        if (!t.critical || t.id == 0) continue;
        surfaces->SetValue(n++, t.id);
        lut->SetTableValue(t.id, t.colour[0] / 255.0, t.colour[1] / 255.0, t.colour[2] / 255.0, 1.0);
    }
    if (n == 0) return nullptr;
    surfaces->ComputeNormalsOn();
    surfaces->ComputeScalarsOn();
    auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    mapper->SetInputConnection(surfaces->GetOutputPort());
    mapper->SetLookupTable(lut);
    mapper->SetScalarRange(-0.5, table.maxId() + 0.5);
    mapper->SetScalarModeToUsePointData();
    mapper->ScalarVisibilityOn();
    auto actor = vtkSmartPointer<vtkActor>::New();
    actor->SetMapper(mapper);
    actor->SetUserMatrix(dataToWorld);
    actor->GetProperty()->SetOpacity(opacity);
    return actor;
}

/// Triangles of @p actor's surface (0 for none), as its mapper last drew them.
std::size_t triangles(vtkActor* actor)
{
    if (!actor) return 0;
    auto* poly = vtkPolyData::SafeDownCast(actor->GetMapper()->GetInput());
    return poly ? std::size_t(poly->GetNumberOfPolys()) : 0;
}

} // namespace

struct VolumeView3d::Impl {
    ViewFrame frame;
    Overlays overlays;
    OverlayStyle style;
    vtkSmartPointer<vtkRenderWindow> window;
    vtkSmartPointer<vtkRenderer> renderer;
    vtkSmartPointer<vtkRenderer> lines; ///< where paths and needles go: the scene, or a layer above it
    vtkSmartPointer<vtkActor> needle;
    RayCaster caster = RayCaster::Gpu;
    View3dStyle look;
    double step = 1.0, far = 1.0;          ///< full-quality ray step [mm]; camera distance [mm]
    vtkSmartPointer<vtkVolumeMapper> full; ///< the ray caster of full-quality frames (and Subsample, AutoRate)
    vtkSmartPointer<vtkVolume> volume;
    vtkSmartPointer<vtkVolumeProperty> property;
    vtkSmartPointer<vtkVolume> shrunk; ///< MovingPath::Shrunk: built at the first moving frame
    RenderQuality last = RenderQuality::Full;
    vtkSmartPointer<vtkImageData> scalars; ///< the RenderVolume's array (shared, not copied)
    vtkSmartPointer<vtkMatrix4x4> dataToWorld;
    Vec3d spacing{1, 1, 1};
    vtkSmartPointer<vtkImageData> labels;     ///< the RenderVolume's label map (shared), if surfaces are drawn
    std::optional<volume::TissueTable> table; ///< a copy: the caller's table need not outlive the view
    vtkSmartPointer<vtkActor> surfaces;       ///< critical surfaces at the labels' own resolution (full quality)
    vtkSmartPointer<vtkActor>
        movingSurfaces; ///< the same, labels sampled at the moving ray step: built at the first moving frame

    /// A ray caster of the view's kind on @p input, @p imageSample pixels per ray, steps of @p stepMm.
    vtkSmartPointer<vtkVolumeMapper> makeMapper(vtkImageData* input, double stepMm) const;
    void setQuality(RenderQuality q);
};

namespace {

/// The frame rate AutoRate asks VTK for while moving, and the still rate it
/// restores (VTK's defaults for vtkRenderWindowInteractor: 15 and 0.0001) [1/s].
constexpr double kMovingRate = 10.0;
constexpr double kStillRate = 0.0001;

void setImageSample(vtkVolumeMapper* m, double pixels, double stepMm, bool autoAdjust)
{
    if (auto* cpu = vtkFixedPointVolumeRayCastMapper::SafeDownCast(m)) {
        cpu->SetAutoAdjustSampleDistances(autoAdjust);
        cpu->SetImageSampleDistance(float(pixels));
        cpu->SetSampleDistance(float(stepMm));
    } else if (auto* gpu = vtkGPUVolumeRayCastMapper::SafeDownCast(m)) {
        gpu->SetAutoAdjustSampleDistances(autoAdjust);
        gpu->SetImageSampleDistance(float(pixels));
        gpu->SetSampleDistance(float(stepMm));
    }
}

} // namespace

vtkSmartPointer<vtkVolumeMapper> VolumeView3d::Impl::makeMapper(vtkImageData* input, double stepMm) const
{
    vtkSmartPointer<vtkVolumeMapper> mapper;
    if (caster == RayCaster::Gpu)
        mapper = vtkSmartPointer<vtkGPUVolumeRayCastMapper>::New();
    else
        mapper = vtkSmartPointer<vtkFixedPointVolumeRayCastMapper>::New();
    setImageSample(mapper, 1.0, stepMm, false); // one ray per pixel
    mapper->SetInputData(input);
    return mapper;
}

void VolumeView3d::Impl::setQuality(RenderQuality q)
{
    const bool moving = q == RenderQuality::Moving;
    const int k = std::max(1, look.movingFactor);
    window->SetDesiredUpdateRate(moving && look.moving == MovingPath::AutoRate ? kMovingRate : kStillRate);
    switch (look.moving) {
    case MovingPath::Subsample:
        setImageSample(full, moving ? k : 1.0, moving ? k * step : step, false);
        property->SetInterpolationType(moving ? VTK_NEAREST_INTERPOLATION : VTK_LINEAR_INTERPOLATION);
        break;
    case MovingPath::AutoRate:
        setImageSample(full, 1.0, step, moving);
        break;
    case MovingPath::Shrunk:
        if (moving && !shrunk) {
            auto shrink = vtkSmartPointer<vtkImageShrink3D>::New();
            shrink->SetInputData(scalars);
            const std::array<int, 3> f = shrinkFactors(k * spacing.minCoeff(), spacing);
            shrink->SetShrinkFactors(f[0], f[1], f[2]);
            shrink->AveragingOn();
            shrink->Update();
            vtkSmartPointer<vtkImageData> copy = shrink->GetOutput();
            shrunk = vtkSmartPointer<vtkVolume>::New();
            const vtkSmartPointer<vtkVolumeMapper> reduced = makeMapper(copy, k * step);
            reduced->SetBlendMode(full->GetBlendMode());
            shrunk->SetMapper(reduced);
            shrunk->SetProperty(property);
            shrunk->SetUserMatrix(dataToWorld);
            renderer->AddVolume(shrunk);
        }
        volume->SetVisibility(!moving);
        if (shrunk) shrunk->SetVisibility(moving);
        break;
    }
    // The critical surfaces while moving: from the label map sampled at the
    // moving frame's ray step (k full steps), no finer than its rays see.
    // Drawn through the software GL, the 256³ torso phantom's full surfaces
    // (~290 000 triangles) took 0.11 s of a 0.15 s moving frame; sampled so,
    // they have ~25 000 (`voxhap bench render` prints both counts). Sampling,
    // not averaging: a label has no mean. And opaque: VTK's order-independent
    // translucency, a few full-screen passes in software, took 0.022 s of a
    // 0.107 s moving frame on the segmented CT (0.085 s opaque).
    if (surfaces && k > 1) {
        if (moving && !movingSurfaces) {
            auto sample = vtkSmartPointer<vtkImageShrink3D>::New();
            sample->SetInputData(labels);
            const std::array<int, 3> f = shrinkFactors(k * step, spacing);
            sample->SetShrinkFactors(f[0], f[1], f[2]);
            sample->AveragingOff();
            sample->Update();
            vtkSmartPointer<vtkImageData> coarse = sample->GetOutput();
            movingSurfaces = criticalSurfaceActor(coarse, *table, dataToWorld, 1.0);
            if (movingSurfaces) renderer->AddActor(movingSurfaces);
        }
        surfaces->SetVisibility(!moving);
        if (movingSurfaces) movingSurfaces->SetVisibility(moving);
    }
    last = q;
}

VolumeView3d::VolumeView3d(const RenderVolume& v, const ViewFrame& frame, const View3dStyle& style,
    const volume::TissueTable& table, const Overlays& overlays)
    : mImpl(std::make_unique<Impl>())
{
    // VTK's X11 window aborts the process when it cannot connect: check first.
    const char* display = std::getenv("DISPLAY");
    if (!display || !displayReachable(display)) throw ValueError("3d view: no X display (start one, or install xvfb)");
    Impl& m = *mImpl;
    m.frame = frame;
    m.overlays = overlays;
    const RenderVolume::Impl& d = v.impl();

    // The volume: the RenderVolume's array itself, placed in the world by a matrix.
    m.caster = style.caster;
    if (m.caster == RayCaster::Auto) m.caster = style.mode == BlendMode::Sum ? RayCaster::Gpu : RayCaster::Cpu;
    if (m.caster == RayCaster::Cpu && style.mode == BlendMode::Sum) {
        throw ValueError("3d view: the CPU ray caster has no summed projection (use the GPU one)");
    }
    m.look = style;
    m.scalars = d.scalars;
    m.dataToWorld = d.dataToWorld();
    m.spacing = d.spacing;
    m.step = std::max(1e-3, style.sampleVoxels) * d.spacing.minCoeff();
    const vtkSmartPointer<vtkVolumeMapper> mapper = m.makeMapper(d.scalars, m.step);
    m.full = mapper;
    auto colour = vtkSmartPointer<vtkColorTransferFunction>::New();
    auto opacity = vtkSmartPointer<vtkPiecewiseFunction>::New();
    auto property = vtkSmartPointer<vtkVolumeProperty>::New();
    m.property = property;
    property->SetInterpolationTypeToLinear();
    const double depthMm = (d.bounds.max - d.bounds.min).cwiseAbs().dot(frame.normal.cwiseAbs());
    switch (style.mode) {
    case BlendMode::Colour:
        mapper->SetBlendModeToComposite();
        if (d.channel == ScalarChannel::Hu) {
            colourTransfer(table, d, colour, opacity);
        } else { // MR values do not follow the table's CT numbers: grey over the body's own range
            greyRamp(style.window, colour);
            opacity->AddPoint(style.window.level - 0.5 * style.window.width, 0.0);
            opacity->AddPoint(style.window.level + 0.5 * style.window.width, kCriticalOpacity);
        }
        if (style.shade) property->ShadeOn();
        break;
    case BlendMode::Grey:
        // Opacity follows the grey ramp (a soft-tissue haze), then on CT rises to
        // bone; MR has no bone value, so its ramp ends at the window's top.
        mapper->SetBlendModeToComposite();
        greyRamp(style.window, colour);
        opacity->AddPoint(style.window.level - 0.5 * style.window.width, 0.0);
        opacity->AddPoint(style.window.level + 0.5 * style.window.width, kSoftOpacity);
        if (d.channel == ScalarChannel::Hu) {
            opacity->AddPoint(std::max(kBoneHu, style.window.level + 0.5 * style.window.width + 1.0), kBoneOpacity);
        }
        if (style.shade) property->ShadeOn();
        break;
    case BlendMode::Mip:
        mapper->SetBlendModeToMaximumIntensity();
        greyRamp(style.window, colour);
        opacity->AddPoint(d.lo, 1.0);
        opacity->AddPoint(d.hi, 1.0);
        break;
    case BlendMode::Sum: {
        // The mapper sums opacity × value along the ray, the value scaled to
        // 0..1 over the array's range, the opacity per unit length: a constant
        // opacity makes the sum a line integral. Scale it so that a ray through
        // the whole depth of average tissue reaches kSumDepthGrey.
        mapper->SetBlendModeToAdditive();
        const double range = std::max(1e-9, d.hi - d.lo);
        const double tissue = std::max(1e-6, (d.tissueMean - d.lo) / range);
        const double a = std::clamp(kSumDepthGrey / (tissue * std::max(1.0, depthMm)), 0.0, 1.0);
        opacity->AddPoint(d.lo, a);
        opacity->AddPoint(d.hi, a);
        greyRamp(WindowLevel{range, 0.5 * (d.lo + d.hi)}, colour);
        break;
    }
    }
    property->SetColor(colour);
    property->SetScalarOpacity(opacity);
    property->SetScalarOpacityUnitDistance(1.0); // opacities are per millimetre
    property->SetAmbient(0.4);
    property->SetDiffuse(0.6);
    property->SetSpecular(0.1);
    auto volumeProp = vtkSmartPointer<vtkVolume>::New();
    volumeProp->SetMapper(mapper);
    volumeProp->SetProperty(property);
    volumeProp->SetUserMatrix(d.dataToWorld());
    m.volume = volumeProp;

    m.renderer = vtkSmartPointer<vtkRenderer>::New();
    m.renderer->SetBackground(0.0, 0.0, 0.0);
    m.renderer->AddVolume(volumeProp);
    // A projection (MIP, sum) has no depth order and writes over any geometry
    // inside the volume: its lines go on a layer above, as on a CT console.
    // Composite modes keep them in the scene, hidden by what lies in front.
    const bool projection = style.mode == BlendMode::Mip || style.mode == BlendMode::Sum;
    m.lines = m.renderer;
    if (projection || style.linesOnTop) {
        m.lines = vtkSmartPointer<vtkRenderer>::New();
        m.lines->SetLayer(1);
        m.lines->SetActiveCamera(m.renderer->GetActiveCamera());
    }

    // Critical structures: one surface pass over the label map for all of them.
    if (style.criticalSurfaces && d.labels) {
        m.labels = d.labels;
        m.table = table;
        m.surfaces = criticalSurfaceActor(d.labels, table, m.dataToWorld, kSurfaceOpacity);
        if (m.surfaces) m.renderer->AddActor(m.surfaces);
    }

    // Paths and needles as 3D lines; entry and target as points.
    std::vector<std::pair<Vec3d, Vec3d>> paths, needles;
    std::vector<Vec3d> entries, targets;
    for (const planning::PlannedPath& p : overlays.paths) {
        paths.emplace_back(p.entry, p.target);
        entries.push_back(p.entry);
        targets.push_back(p.target);
        if (p.needle) {
            for (const auto& segment : p.needle->segments()) needles.push_back(segment);
        }
    }
    if (!paths.empty()) {
        m.lines->AddActor(lineActor(paths, m.style.path, 2.0));
        m.lines->AddActor(pointActor(entries, m.style.entry, 10.0));
        m.lines->AddActor(pointActor(targets, m.style.target, 10.0));
    }
    if (!needles.empty()) m.lines->AddActor(lineActor(needles, m.style.needle, 3.0));
    setNeedle(overlays.needle);

    m.far = (d.bounds.max - d.bounds.min).norm() + 1.0;
    m.renderer->GetActiveCamera()->ParallelProjectionOn();
    setCamera(frame);

    m.window = vtkSmartPointer<vtkRenderWindow>::New();
    m.window->SetOffScreenRendering(1);
    m.window->SetMultiSamples(0);
    m.window->SetSize(frame.width, frame.height);
    m.window->AddRenderer(m.renderer);
    if (m.lines != m.renderer) {
        m.window->SetNumberOfLayers(2);
        m.window->AddRenderer(m.lines);
    }
    // VTK 9.1's vtkViewport::ComputeAspect skips its work when the window size,
    // viewport and pixel aspect equal those it last computed with, and those
    // remembered values are not initialised: a renderer allocated where an
    // earlier one lived can find them equal and keep the default aspect 1 : 1.
    // The CPU ray caster reads that aspect for its rays (the GL geometry does
    // not), so about one view in six drew the volume stretched sideways under
    // correctly placed surfaces. The window's size is fixed: set the aspect.
    for (vtkRenderer* r : {m.renderer.Get(), m.lines.Get()}) r->SetAspect(double(frame.width) / frame.height, 1.0);
}

VolumeView3d::~VolumeView3d()
{
    if (mImpl && mImpl->window) mImpl->window->Finalize(); // release the GL context while the display is up
}

RayCaster VolumeView3d::caster() const { return mImpl->caster; }

RenderQuality VolumeView3d::lastQuality() const { return mImpl->last; }

std::size_t VolumeView3d::criticalTriangles() const
{
    const Impl& m = *mImpl;
    const bool coarse = m.last == RenderQuality::Moving && m.movingSurfaces && m.movingSurfaces->GetVisibility();
    return triangles(coarse ? m.movingSurfaces : m.surfaces);
}

void VolumeView3d::setCamera(const ViewFrame& frame)
{
    // A parallel projection onto the frame: pixel (x, y) shows the ray through frame.toWorld(x, y).
    Impl& m = *mImpl;
    if (frame.width != m.frame.width || frame.height != m.frame.height)
        throw ValueError("3d view: a camera frame must keep the view's size in pixels");
    m.frame = frame;
    vtkCamera* cam = m.renderer->GetActiveCamera();
    const Vec3d centre = frame.centre();
    const Vec3d eye = centre - m.far * frame.normal;
    cam->SetFocalPoint(centre.data());
    cam->SetPosition(eye.data());
    const Vec3d up = -frame.down;
    cam->SetViewUp(up.data());
    cam->SetParallelScale(0.5 * frame.height * frame.pixelMm);
    cam->SetClippingRange(0.5, 3.0 * m.far);
}

void VolumeView3d::setNeedle(const std::optional<planning::NeedlePose>& needle)
{
    Impl& m = *mImpl;
    if (m.needle) m.lines->RemoveActor(m.needle);
    m.needle = nullptr;
    if (!needle) return;
    m.needle = lineActor(needle->segments(), m.style.needle, 3.0);
    m.lines->AddActor(m.needle);
}

Image VolumeView3d::render(RenderQuality quality)
{
    Impl& m = *mImpl;
    m.setQuality(quality);
    m.window->Render();
    auto grab = vtkSmartPointer<vtkWindowToImageFilter>::New();
    grab->SetInput(m.window);
    grab->SetInputBufferTypeToRGB();
    grab->ReadFrontBufferOff();
    grab->Update();
    vtkImageData* shot = grab->GetOutput();
    int dims[3];
    shot->GetDimensions(dims);
    const auto* p = static_cast<const std::uint8_t*>(shot->GetScalarPointer());
    Image img(dims[0], dims[1]);
    for (int y = 0; y < dims[1]; ++y) { // VTK's rows start at the bottom
        const std::uint8_t* row = p + std::size_t(dims[1] - 1 - y) * std::size_t(dims[0]) * 3;
        for (int x = 0; x < dims[0]; ++x) img.at(x, y) = {row[3 * x], row[3 * x + 1], row[3 * x + 2]};
    }
    drawAnnotations(img, m.frame, m.overlays, m.style);
    return img;
}

} // namespace voxhap::render
