// SPDX-License-Identifier: Apache-2.0
/// @file FusionViews.h
/// @brief Views to judge a CT–MR registration by eye, in the three planes: a
/// checkerboard of CT and MR tiles, the CT's bone edges drawn over the MR, and
/// the MR in colour over the CT in grey. Drawn for the registered MR and for
/// the MR at its header geometry, side by side (docs/guide.md "One patient, two
/// scans"). No display and no GL: slices only.
#pragma once

#include "render/raster/Image.h"
#include "render/views/ViewTypes.h"

#include <array>
#include <string>

namespace voxhap::volume {
class Volume;
}

namespace voxhap::render {

struct FusionViewStyle {
    double checkerMm = 20.0; ///< side of a checkerboard tile [mm]
    double boneHu = 300.0;   ///< the CT's bone edge: where HU crosses this [chosen: cortical and cancellous bone, above
                             ///< contrast-filled vessels]
    double colourOpacity = 0.5; ///< of the MR's colour over the CT
    double pixelMm = 0.0;       ///< pixel size [mm]; 0: the CT's finest voxel, coarsened to fit maxPixels
    int maxPixels = 384;        ///< largest side of one panel [px]
};

/// @brief One plane's three panels.
struct FusionPanels {
    Image checkerboard, boneEdges, colour;
};

/// @brief The three panels of plane @p view through @p point. @p ct holds the
/// hu grid, @p mr the MR channel (t1 or intensity) on the same grid.
/// @throw ValueError if either lacks its channel
FusionPanels renderFusionPanels(const volume::Volume& ct, const volume::Volume& mr, ViewKind view, const Vec3d& point,
    const FusionViewStyle& style = {});

/// @brief One plane's sheet: the header geometry's panels above the registered
/// ones, each row titled, each column named.
Image fusionSheet(const FusionPanels& before, const FusionPanels& after, const std::string& title);

} // namespace voxhap::render
