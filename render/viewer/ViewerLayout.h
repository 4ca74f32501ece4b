// SPDX-License-Identifier: Apache-2.0
/// @file ViewerLayout.h
/// @brief Where the viewer's four panes sit in its window, and which pane a
/// window pixel falls in: pure geometry, testable without a display.
///
/// Two by two, as on a CT console: axial top left, sagittal top right,
/// coronal bottom left, 3D bottom right, separated by a gap; a status bar
/// runs along the bottom of the window.
#pragma once

#include "render/raster/Image.h"
#include "render/views/ViewTypes.h"

#include <array>
#include <optional>

namespace voxhap::render {

/// @brief A pane: the window pixels [x, x + width) × [y, y + height).
struct PaneRect {
    ViewKind view = ViewKind::Axial;
    int x = 0, y = 0, width = 0, height = 0;
    bool contains(int px, int py) const { return px >= x && py >= y && px < x + width && py < y + height; }
};

struct ViewerLayout {
    int width = 0, height = 0;     ///< window [px]
    std::array<PaneRect, 4> panes; ///< axial, sagittal, coronal, 3d
    const PaneRect& pane(ViewKind v) const;
};

/// @brief The layout of a @p width × @p height window.
/// @throw ValueError if a pane would be smaller than 16 px on a side
ViewerLayout viewerLayout(int width, int height, int statusPx, int gapPx = 4);

/// @brief Where an image of @p imageWidth × @p imageHeight sits in @p pane:
/// centred (its top-left, in window pixels; a larger image is centred and cropped).
Vec2d imageOrigin(const PaneRect& pane, int imageWidth, int imageHeight);

/// @brief A window pixel, as a pane and a position in that pane's image.
struct PaneHit {
    ViewKind view = ViewKind::Axial;
    Vec2d px{0, 0}; ///< in the pane image's pixels (x right, y down, centres at integers)
};

/// @brief The pane under window pixel (@p x, @p y) and the position in its image
/// (placed by imageOrigin); nullopt on a gap or the status bar.
std::optional<PaneHit> hitPane(
    const ViewerLayout& layout, int x, int y, const std::array<std::array<int, 2>, 4>& imageSizes);

} // namespace voxhap::render
