// SPDX-License-Identifier: Apache-2.0
/// @file Draw.h
/// @brief Lines, rings and text drawn into an Image in software: the overlays
/// of every view (the GL-free slice path has nothing else to draw with).
#pragma once

#include "render/raster/Image.h"

#include <string_view>

namespace voxhap::render {

/// @brief How a line or ring is drawn.
struct Stroke {
    Rgb colour{255, 255, 255};
    double widthPx = 1.0; ///< line width [px]
    double dashPx = 0.0;  ///< dash and gap length [px]; 0: solid
    double alpha = 1.0;   ///< opacity in [0, 1]
};

/// @brief A line from @p a to @p b (pixel coordinates, centres at integers).
/// A dashed line starts and ends on a dash, so both end pixels are always drawn.
void drawLine(Image& img, const Vec2d& a, const Vec2d& b, const Stroke& s);

/// @brief A ring of radius @p radiusPx around @p centre.
void drawRing(Image& img, const Vec2d& centre, double radiusPx, const Stroke& s);

/// @brief A filled disc of radius @p radiusPx.
void fillDisc(Image& img, const Vec2d& centre, double radiusPx, Rgb colour, double alpha = 1.0);

/// @brief Width and height of @p text at integer @p scale [px].
int textWidth(std::string_view text, int scale);
int textHeight(int scale);

/// @brief Draw @p text (printable ASCII, BitmapFont.h) with its top-left at (@p x, @p y),
/// each font pixel a @p scale × @p scale block. With @p shadow, a black copy one
/// block down and right keeps it legible on any background.
void drawText(Image& img, int x, int y, std::string_view text, Rgb colour, int scale, bool shadow = true);

} // namespace voxhap::render
