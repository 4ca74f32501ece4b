// SPDX-License-Identifier: Apache-2.0
/// @file Snapshot.cpp
#include "render/outputs/Snapshot.h"

#include "core/Errors.h"
#include "render/slices/SliceView.h"
#include "render/views/RenderVolume.h"
#include "render/volume3d/VolumeView3d.h"
#include "volume/Volume.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace voxhap::render {

struct Snapshot::View3d {
    std::unique_ptr<VolumeView3d> view;
};

namespace {

bool has(const std::vector<ViewKind>& views, ViewKind v)
{
    return std::find(views.begin(), views.end(), v) != views.end();
}

} // namespace

Snapshot::Snapshot(const volume::Volume& v, const RenderRequest& request, const volume::TissueTable& table)
    : mRequest(request), mTable(table)
{
    if (mRequest.views.empty()) throw ValueError("render: no view requested");
    const bool slices = has(mRequest.views, ViewKind::Axial) || has(mRequest.views, ViewKind::Sagittal) ||
        has(mRequest.views, ViewKind::Coronal);
    const bool threeD = has(mRequest.views, ViewKind::ThreeD);
    const bool labels = (slices && mRequest.labels) || (threeD && mRequest.criticalSurfaces);
    mVolume = std::make_unique<RenderVolume>(v, labels);

    const WorldBounds box = mVolume->worldBounds();
    const Vec3d centre = 0.5 * (box.min + box.max);
    mPoint = mRequest.point            ? *mRequest.point
        : !mRequest.plan.paths.empty() ? mRequest.plan.paths.front().target
                                       : centre;
    const double pixel = mRequest.pixelMm > 0.0 ? mRequest.pixelMm : mVolume->finestSpacing();
    for (ViewKind k : mRequest.views) {
        mFrames.emplace_back(k, viewFrame(k, box, k == ViewKind::ThreeD ? centre : mPoint, pixel, mRequest.maxPixels));
    }
}

Snapshot::~Snapshot() = default;

const ViewFrame& Snapshot::frame(ViewKind v) const
{
    for (const auto& [k, f] : mFrames) {
        if (k == v) return f;
    }
    throw ValueError("render: the " + std::string(viewName(v)) + " view was not requested");
}

Image Snapshot::render(ViewKind v)
{
    const ViewFrame& f = frame(v);
    Overlays o;
    o.paths = mRequest.plan.paths;
    o.needle = mRequest.needle;
    // MR says what its grey means (a window of its own values, ms or arbitrary
    // units); CT keeps its familiar look, the presets' HU.
    const bool mr = mVolume->channel() != ScalarChannel::Hu;
    if (v != ViewKind::ThreeD) {
        o.crosshair = mPoint;
        o.title = sliceTitle(v, mPoint);
        SliceStyle style;
        style.window = mRequest.window ? *mRequest.window : mVolume->defaultWindow();
        if (mr) o.legend = windowLegend(mVolume->channel(), style.window);
        style.labels = mRequest.labels;
        Image img = renderSlice(*mVolume, f, style, mTable);
        drawSliceOverlays(img, f, o, OverlayStyle{});
        return img;
    }
    if (!m3d) {
        View3dStyle style;
        style.mode = mRequest.mode;
        style.caster = mRequest.caster;
        style.criticalSurfaces = mRequest.criticalSurfaces;
        style.shade = mRequest.shade3d;
        style.linesOnTop = mRequest.linesOnTop3d;
        style.window = mRequest.window ? *mRequest.window : mVolume->defaultWindow(mRequest.mode);
        o.title = "3d " + std::string(blendModeName(mRequest.mode));
        if (mr && mRequest.mode != BlendMode::Sum) { // the sum has no window
            o.legend = windowLegend(mVolume->channel(), style.window);
        }
        m3d = std::make_unique<View3d>();
        m3d->view = std::make_unique<VolumeView3d>(*mVolume, f, style, mTable, o);
    }
    return m3d->view->render(mRequest.quality3d);
}

Image contactSheet(const std::vector<Image>& views)
{
    if (views.empty()) throw ValueError("contact sheet: no views");
    constexpr int kGapPx = 4;
    const Rgb gap{60, 60, 60};
    int cw = 1, ch = 1;
    for (const Image& v : views) cw = std::max(cw, v.width()), ch = std::max(ch, v.height());
    const int cols = std::min<int>(2, int(views.size()));
    const int rows = (int(views.size()) + cols - 1) / cols;
    Image sheet(cols * cw + (cols - 1) * kGapPx, rows * ch + (rows - 1) * kGapPx, gap);
    for (std::size_t i = 0; i < views.size(); ++i) {
        const int cx = int(i) % cols * (cw + kGapPx), cy = int(i) / cols * (ch + kGapPx);
        sheet.fill(cx, cy, cx + cw, cy + ch, Rgb{});
        sheet.paste(views[i], cx + (cw - views[i].width()) / 2, cy + (ch - views[i].height()) / 2);
    }
    return sheet;
}

} // namespace voxhap::render
