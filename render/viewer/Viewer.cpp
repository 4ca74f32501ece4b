// SPDX-License-Identifier: Apache-2.0
/// @file Viewer.cpp
#include "render/viewer/Viewer.h"

#include "core/Errors.h"
#include "render/raster/Draw.h"
#include "render/slices/SliceView.h"
#include "render/views/Overlays.h"
#include "render/views/RenderVolume.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace voxhap::render {

namespace {

constexpr int kViewerStatusPx = 24;      ///< two lines of 5×7 text with their padding
const Rgb kViewerBackground{30, 30, 30}; ///< panes' margins and the status bar
const Rgb kMeasureColour{255, 230, 0};   ///< distance and angle segments, picked points
const WindowPreset kViewerPresets[] = {WindowPreset::SoftTissue, WindowPreset::Bone, WindowPreset::Lung};

std::string fixed1(double v)
{
    std::ostringstream os;
    os << std::fixed << std::setprecision(1) << v;
    return os.str();
}

} // namespace

Viewer::Viewer(const volume::Volume& v, const ViewerOptions& options, const volume::TissueTable& table)
    : mOpt(options), mTable(table), mEditor(options.plan)
{
    mLayout = viewerLayout(mOpt.width, mOpt.height, kViewerStatusPx);
    mVolume = std::make_unique<RenderVolume>(v, true);
    mBox = mVolume->worldBounds();
    const Vec3d centre = 0.5 * (mBox.min + mBox.max);
    mPoint = mOpt.point ? *mOpt.point : !mOpt.plan.paths.empty() ? mOpt.plan.paths.front().target : centre;
    mStepMm = mVolume->finestSpacing();
    // One pixel size for all panes, so that a millimetre looks the same in each:
    // the largest view fills its pane (magnified beyond the voxels if need be,
    // as a console zooms a small field of view).
    const Vec3d ext = mBox.max - mBox.min;
    mPixelMm = 0.0;
    for (const PaneRect& p : mLayout.panes) {
        Vec3d right, down;
        viewAxes(p.view, right, down);
        const double w = std::abs(ext.dot(right)), h = std::abs(ext.dot(down));
        mPixelMm = std::max({mPixelMm, w / p.width, h / p.height});
    }
    mWindow = mOpt.window ? *mOpt.window : mVolume->defaultWindow();
    mFrames[std::size_t(ViewKind::ThreeD)] = viewFrame(ViewKind::ThreeD, mBox, centre, mPixelMm, 1 << 20);
    mCamera = OrbitCamera(mFrames[std::size_t(ViewKind::ThreeD)]);
    updateFrames();
}

Viewer::~Viewer() = default;

void Viewer::updateFrames()
{
    for (ViewKind k : {ViewKind::Axial, ViewKind::Sagittal, ViewKind::Coronal}) {
        mFrames[std::size_t(k)] = viewFrame(k, mBox, mPoint, mPixelMm, 1 << 20);
        mSliceStale[std::size_t(k)] = true;
    }
    mDirty = true;
}

Vec2d Viewer::imageOrigin(ViewKind v) const
{
    const ViewFrame& f = frame(v);
    return render::imageOrigin(mLayout.pane(v), f.width, f.height);
}

bool Viewer::clickWindow(int x, int y)
{
    std::array<std::array<int, 2>, 4> sizes{};
    for (std::size_t i = 0; i < 4; ++i) sizes[i] = {mFrames[i].width, mFrames[i].height};
    const auto hit = hitPane(mLayout, x, y, sizes);
    mDragFrom.reset();
    if (!hit) return true;
    if (hit->view == ViewKind::ThreeD) mDragFrom = Vec2d(x, y); // a drag may follow
    ViewerEvent e;
    e.kind = ViewerEvent::Kind::Click;
    e.pane = hit->view;
    e.px = hit->px;
    return handle(e);
}

void Viewer::scrollWindow(int x, int y, int steps)
{
    for (const PaneRect& p : mLayout.panes) {
        if (!p.contains(x, y)) continue;
        ViewerEvent e;
        e.kind = ViewerEvent::Kind::Scroll;
        e.pane = p.view;
        e.steps = steps;
        handle(e);
    }
}

void Viewer::dragWindow(int x, int y)
{
    if (!mDragFrom) return;
    ViewerEvent e;
    e.kind = ViewerEvent::Kind::Drag;
    e.pane = ViewKind::ThreeD;
    e.px = Vec2d(x, y) - *mDragFrom;
    mDragFrom = Vec2d(x, y);
    handle(e);
}

void Viewer::releaseWindow()
{
    if (!mDragFrom) return;
    mDragFrom.reset();
    ViewerEvent e;
    e.kind = ViewerEvent::Kind::Release;
    e.pane = ViewKind::ThreeD;
    handle(e);
}

void Viewer::cameraMoved(bool dragging)
{
    mFrames[std::size_t(ViewKind::ThreeD)] = mCamera.frame();
    mMoving = true;
    mDragging = dragging;
    mSettleAt = std::chrono::steady_clock::now() +
        std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(kSettleS));
    m3dStale = true;
}

bool Viewer::settle(std::chrono::steady_clock::time_point now)
{
    if (!mMoving || mDragging || now < mSettleAt) return false;
    mMoving = false;
    m3dStale = true;
    mDirty = true;
    return true;
}

bool Viewer::handle(const ViewerEvent& e)
{
    mMessage.clear();
    mDirty = true;
    switch (e.kind) {
    case ViewerEvent::Kind::Click: {
        if (e.pane == ViewKind::ThreeD) {
            mMessage =
                "the 3d pane has no depth to pick: click a slice (drag rotates the 3d pane, wheel zooms, r resets)";
            return true;
        }
        mActive = e.pane;
        const ViewFrame& f = frame(e.pane);
        if (e.px.x() < -0.5 || e.px.y() < -0.5 || e.px.x() > f.width - 0.5 || e.px.y() > f.height - 0.5) {
            mMessage = "outside the image";
            return true;
        }
        if (const auto moved = mEditor.click(f.toWorld(e.px))) {
            mPoint = *moved;
            updateFrames();
        }
        return true;
    }
    case ViewerEvent::Kind::Drag:
        if (e.pane == ViewKind::ThreeD && mOpt.threeD) {
            mCamera.drag(e.px.x(), e.px.y());
            cameraMoved(true);
        }
        return true;
    case ViewerEvent::Kind::Release:
        if (mDragging) {
            mDragging = false;
            mMoving = false; // the drag ended: full quality at the next render
            m3dStale = true;
        }
        return true;
    case ViewerEvent::Kind::Scroll: {
        if (e.pane == ViewKind::ThreeD) {
            if (!mOpt.threeD) return true;
            mCamera.wheel(e.steps);
            cameraMoved(false);
            return true;
        }
        mActive = e.pane;
        mPoint += double(e.steps) * mStepMm * frame(e.pane).normal;
        // Keep the crosshair inside the volume: a slice beyond it shows only air.
        mPoint = mPoint.cwiseMax(mBox.min).cwiseMin(mBox.max);
        updateFrames();
        return true;
    }
    case ViewerEvent::Kind::Key:
        break;
    }
    const std::string& k = e.key;
    if (k == "q" || k == "Escape") return false;
    if (k == "n")
        mEditor.setTool(Tool::Navigate);
    else if (k == "p")
        mEditor.setTool(Tool::Plan);
    else if (k == "d")
        mEditor.setTool(Tool::Distance);
    else if (k == "a")
        mEditor.setTool(Tool::Angle);
    else if (k == "c")
        mEditor.clearMeasurements();
    else if (k == "s")
        savePlan();
    else if (k == "r") {
        mCamera.reset();
        mFrames[std::size_t(ViewKind::ThreeD)] = mCamera.frame();
        mMoving = mDragging = false;
        m3dStale = true;
    } else if (k == "w" && mVolume->channel() == ScalarChannel::Hu) {
        mWindowPreset = (mWindowPreset + 1) % 3;
        mWindow = windowLevel(kViewerPresets[mWindowPreset]);
        mSliceStale = {true, true, true};
    } else if (k == "w") { // HU presets mean nothing on MR
        mMessage = "w: CT windows do not apply to MR; the window stays " + windowLegend(mVolume->channel(), mWindow);
    } else if (k == "Up" || k == "Page_Up" || k == "Down" || k == "Page_Down") {
        ViewerEvent s;
        s.kind = ViewerEvent::Kind::Scroll;
        s.pane = mActive;
        s.steps = (k == "Up" || k == "Page_Up") ? 1 : -1;
        return handle(s);
    }
    return true;
}

void Viewer::savePlan()
{
    if (mEditor.plan().paths.empty()) { // an edited path is in the plan
        mMessage = "nothing to save: click an entry and a target with the plan tool (p)";
        return;
    }
    // A failed save must not end an interactive session: say so in the status
    // bar and keep the error for a scripted run to report.
    try {
        planning::savePlan(mEditor.plan(), mOpt.planOut);
        mMessage = "saved " + mOpt.planOut.string();
        mSaveError.clear();
    } catch (const std::exception& e) {
        mSaveError = e.what();
        mMessage = "not saved: " + mSaveError;
    }
}

void Viewer::setNeedle(const std::optional<planning::NeedlePose>& needle)
{
    mNeedle = needle;
    mDirty = true; // the 3D picture is kept: the needle is drawn over it
}

void Viewer::setNote(std::string note)
{
    if (note != mNote) mDirty = true;
    mNote = std::move(note);
}

void Viewer::invalidate()
{
    mSliceStale = {true, true, true};
    m3dStale = true;
    mDirty = true;
}

std::string Viewer::status() const
{
    std::string s = mEditor.status();
    if (!mMessage.empty()) s += " | " + mMessage;
    return s;
}

Image Viewer::renderSlicePane(ViewKind v)
{
    const std::size_t i = std::size_t(v);
    const ViewFrame& f = mFrames[i];
    if (mSliceStale[i]) {
        SliceStyle style;
        style.window = mWindow;
        style.labels = mOpt.labels;
        mSliceBase[i] = renderSlice(*mVolume, f, style, mTable);
        mSliceStale[i] = false;
    }
    Image img = mSliceBase[i];
    Overlays o;
    o.paths = mEditor.plan().paths;
    o.needle = mNeedle;
    o.crosshair = mPoint;
    o.title = sliceTitle(v, mPoint);
    if (mVolume->channel() != ScalarChannel::Hu) o.legend = windowLegend(mVolume->channel(), mWindow);
    const OverlayStyle style;
    drawSliceOverlays(img, f, o, style);
    // What the editor is picking: points so far, then the finished measurements.
    const Stroke measure{kMeasureColour, 1.0, 0.0, 1.0};
    if (const auto& entry = mEditor.pendingEntry())
        drawRing(img, f.toPixel(*entry), 5.0, Stroke{style.entry, 2.0, 0.0, 1.0});
    for (const Vec3d& p : mEditor.pendingPoints()) drawRing(img, f.toPixel(p), 3.0, measure);
    const int scale = 1;
    if (const auto& d = mEditor.distance()) {
        const Vec2d a = f.toPixel(d->a), b = f.toPixel(d->b);
        drawLine(img, a, b, measure);
        const Vec2d m = 0.5 * (a + b);
        drawText(img, int(m.x()) + 4, int(m.y()) + 4, fixed1(d->lengthMm()) + " mm", kMeasureColour, scale);
    }
    if (const auto& ang = mEditor.angle()) {
        for (const Segment* s : {&ang->first, &ang->second}) drawLine(img, f.toPixel(s->a), f.toPixel(s->b), measure);
        if (const auto deg = angleDeg(ang->first, ang->second)) {
            const Vec2d m = f.toPixel(ang->second.a);
            drawText(img, int(m.x()) + 4, int(m.y()) + 4, fixed1(*deg) + " deg", kMeasureColour, scale);
        }
    }
    return img;
}

Image Viewer::render3dPane()
{
    const ViewFrame& f = frame(ViewKind::ThreeD);
    if (!mOpt.threeD) {
        Image img(f.width, f.height, kViewerBackground);
        const std::string note = "3d: " + (mOpt.threeDNote.empty() ? std::string("off") : mOpt.threeDNote);
        drawText(img, 6, 6, note.substr(0, std::size_t(std::max(1, (f.width - 12) / 6))), Rgb{255, 255, 255}, 1);
        return img;
    }
    if (!m3d) {
        View3dStyle style;
        style.mode = mOpt.mode;
        style.caster = mOpt.caster;
        style.window = mOpt.window ? *mOpt.window : mVolume->defaultWindow(mOpt.mode);
        // Paths and needle are drawn over the cached picture instead (drawOver3d).
        Overlays o;
        o.title = "3d " + std::string(blendModeName(mOpt.mode));
        if (mVolume->channel() != ScalarChannel::Hu && mOpt.mode != BlendMode::Sum) {
            o.legend = windowLegend(mVolume->channel(), style.window); // the sum has no window
        }
        style.moving = mOpt.moving;
        style.movingFactor = mOpt.movingFactor;
        style.sampleVoxels = mOpt.sampleVoxels;
        m3d = std::make_unique<VolumeView3d>(*mVolume, mCamera.home(), style, mTable, o);
    }
    m3d->setCamera(f);
    m3dQuality = mMoving ? RenderQuality::Moving : RenderQuality::Full;
    return m3d->render(m3dQuality);
}

void Viewer::drawOver3d(Image& img) const
{
    // The 3D pane is a parallel projection onto its frame, so the frame's
    // toPixel is exactly where VTK puts a point: lines drawn here land where
    // VTK would draw them, on top as its overlay layer does, and moving the
    // needle costs no volume rendering.
    const ViewFrame& f = frame(ViewKind::ThreeD);
    const OverlayStyle style;
    for (const planning::PlannedPath& p : mEditor.plan().paths) {
        drawLine(img, f.toPixel(p.entry), f.toPixel(p.target), Stroke{style.path, 2.0, 0.0, 1.0});
        fillDisc(img, f.toPixel(p.entry), 4.0, style.entry);
        fillDisc(img, f.toPixel(p.target), 4.0, style.target);
        if (p.needle) {
            for (const auto& [a, b] : p.needle->segments())
                drawLine(img, f.toPixel(a), f.toPixel(b), Stroke{style.needle, 3.0, 0.0, 1.0});
        }
    }
    if (const auto& entry = mEditor.pendingEntry()) fillDisc(img, f.toPixel(*entry), 4.0, style.entry);
    if (mNeedle) {
        for (const auto& [a, b] : mNeedle->segments())
            drawLine(img, f.toPixel(a), f.toPixel(b), Stroke{style.needle, 3.0, 0.0, 1.0});
    }
}

Image Viewer::render()
{
    Image win(mLayout.width, mLayout.height, kViewerBackground);
    for (ViewKind k : {ViewKind::Axial, ViewKind::Sagittal, ViewKind::Coronal}) {
        const Vec2d o = imageOrigin(k);
        win.paste(renderSlicePane(k), int(o.x()), int(o.y()));
    }
    if (m3dStale || m3dImage.empty()) {
        m3dImage = render3dPane();
        m3dStale = false;
    }
    Image pane3d = m3dImage;
    if (mOpt.threeD) drawOver3d(pane3d);
    const Vec2d o3 = imageOrigin(ViewKind::ThreeD);
    win.paste(pane3d, int(o3.x()), int(o3.y()));
    // Status bar: the tool and measurements, then the note (the pose stream).
    const int y0 = mLayout.height - kViewerStatusPx + 3;
    const int maxChars = std::max(1, (mLayout.width - 8) / 6);
    drawText(win, 4, y0, status().substr(0, std::size_t(maxChars)), Rgb{255, 255, 255}, 1, false);
    std::string second =
        "keys: n p d a tools, arrows slice, w window, c clear, s save, q quit; 3d: drag rotate, wheel zoom, r reset";
    if (!mNote.empty()) second = mNote + " | " + second;
    drawText(win, 4, y0 + textHeight(1) + 4, second.substr(0, std::size_t(maxChars)), Rgb{180, 180, 180}, 1, false);
    mDirty = false;
    return win;
}

} // namespace voxhap::render
