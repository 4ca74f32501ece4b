// SPDX-License-Identifier: Apache-2.0
/// @file ViewerLayout.cpp
#include "render/viewer/ViewerLayout.h"

#include "core/Errors.h"

#include <string>

namespace voxhap::render {

namespace {
constexpr int kMinPanePx = 16; // below this a pane shows nothing useful
}

const PaneRect& ViewerLayout::pane(ViewKind v) const { return panes[std::size_t(v)]; }

ViewerLayout viewerLayout(int width, int height, int statusPx, int gapPx)
{
    ViewerLayout l;
    l.width = width, l.height = height;
    const int cw = (width - gapPx) / 2, ch = (height - statusPx - gapPx) / 2;
    if (cw < kMinPanePx || ch < kMinPanePx || gapPx < 0 || statusPx < 0) {
        throw ValueError("viewer: a " + std::to_string(width) + " x " + std::to_string(height) +
            " window is too small for four panes");
    }
    // The right column and bottom row take the odd pixel, so the panes fill the window.
    const int cw2 = width - gapPx - cw, ch2 = height - statusPx - gapPx - ch;
    l.panes[0] = {ViewKind::Axial, 0, 0, cw, ch};
    l.panes[1] = {ViewKind::Sagittal, cw + gapPx, 0, cw2, ch};
    l.panes[2] = {ViewKind::Coronal, 0, ch + gapPx, cw, ch2};
    l.panes[3] = {ViewKind::ThreeD, cw + gapPx, ch + gapPx, cw2, ch2};
    return l;
}

Vec2d imageOrigin(const PaneRect& pane, int imageWidth, int imageHeight)
{
    return {double(pane.x + (pane.width - imageWidth) / 2), double(pane.y + (pane.height - imageHeight) / 2)};
}

std::optional<PaneHit> hitPane(
    const ViewerLayout& layout, int x, int y, const std::array<std::array<int, 2>, 4>& imageSizes)
{
    for (std::size_t i = 0; i < layout.panes.size(); ++i) {
        const PaneRect& p = layout.panes[i];
        if (!p.contains(x, y)) continue;
        const Vec2d o = imageOrigin(p, imageSizes[i][0], imageSizes[i][1]);
        return PaneHit{p.view, Vec2d(x - o.x(), y - o.y())};
    }
    return std::nullopt;
}

} // namespace voxhap::render
