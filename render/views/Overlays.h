// SPDX-License-Identifier: Apache-2.0
/// @file Overlays.h
/// @brief What is drawn over a view, in software: planned paths and the needle
/// (projected onto a slice, and marked where they cross it), the crosshair,
/// a millimetre scale bar, orientation letters, a title and a legend.
#pragma once

#include "planning/PlanFile.h"
#include "render/raster/Image.h"
#include "render/views/ViewFrame.h"

#include <optional>
#include <string>
#include <vector>

namespace voxhap::render {

/// @brief Colours and sizes of the overlays.
struct OverlayStyle {
    Rgb path{0, 220, 255};   ///< planned path
    Rgb entry{60, 230, 60};  ///< entry marker
    Rgb target{255, 60, 60}; ///< target marker
    Rgb needle{255, 150, 0}; ///< needle shaft and tip
    Rgb crosshair{0, 255, 0};
    Rgb letters{255, 255, 0}; ///< orientation letters
    Rgb text{255, 255, 255};  ///< title and scale bar
    /// A path within this distance of a slice's plane is drawn solid ("in the
    /// slice"); farther parts are dashed projections [mm].
    double inPlaneMm = 1.0;
};

/// @brief What to draw over a view.
struct Overlays {
    std::vector<planning::PlannedPath> paths;
    std::optional<planning::NeedlePose> needle;
    std::optional<Vec3d> crosshair; ///< [mm, LPS]
    std::string title;
    bool scaleBar = true;
    bool letters = true;
    std::string legend; ///< a second line under the title: the window and its unit (MR)
};

/// @brief Text scale for an image: 5×7 glyphs at 2× from 400 px up.
int annotationScale(const Image& img);

/// @brief The scale bar's length for an image @p widthMm wide: the largest
/// 1, 2 or 5 × 10ⁿ mm not over a quarter of the width.
double scaleBarLengthMm(double widthMm);

/// @brief Everything: paths, needle and crosshair (slices only; the 3D view
/// draws these as 3D lines), then the annotations.
void drawSliceOverlays(Image& img, const ViewFrame& f, const Overlays& o, const OverlayStyle& s);

/// @brief Scale bar, orientation letters, title and legend only.
void drawAnnotations(Image& img, const ViewFrame& f, const Overlays& o, const OverlayStyle& s);

} // namespace voxhap::render
