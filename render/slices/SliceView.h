// SPDX-License-Identifier: Apache-2.0
/// @file SliceView.h
/// @brief Axial, sagittal and coronal slices as images: the values resampled
/// on the view's plane, windowed to grey, tissue labels blended in their table
/// colours. Needs no display and no GL.
#pragma once

#include "render/raster/Image.h"
#include "render/views/ViewFrame.h"
#include "render/views/ViewTypes.h"

namespace voxhap::volume {
class TissueTable;
}

namespace voxhap::render {

class RenderVolume;

struct SliceStyle {
    WindowLevel window;         ///< grey ramp [HU or the t1 unit]
    bool labels = true;         ///< blend the tissue colours (if the volume has labels)
    double labelOpacity = 0.35; ///< in [0, 1]
};

/// @brief The slice of @p v on @p f's plane, without overlays.
Image renderSlice(const RenderVolume& v, const ViewFrame& f, const SliceStyle& style, const volume::TissueTable& table);

/// @brief Grey level 0..255 of @p value through window @p w.
std::uint8_t windowed(double value, const WindowLevel& w);

} // namespace voxhap::render
