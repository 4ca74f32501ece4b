// SPDX-License-Identifier: Apache-2.0
/// @file Image.cpp
#include "render/raster/Image.h"

#include "core/Errors.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace voxhap::render {

Image::Image(int width, int height, Rgb fill) : mWidth(width), mHeight(height)
{
    // 16384 px a side is far beyond any view and keeps width*height in range.
    if (width < 0 || height < 0 || width > 16384 || height > 16384) {
        throw ValueError("image size " + std::to_string(width) + " x " + std::to_string(height) + " out of range");
    }
    mPixels.assign(std::size_t(width) * std::size_t(height), fill);
}

void Image::blend(int x, int y, Rgb c, double alpha)
{
    if (!contains(x, y)) return;
    const double a = std::clamp(alpha, 0.0, 1.0);
    Rgb& p = at(x, y);
    const auto mix = [a](std::uint8_t under, std::uint8_t over) {
        return std::uint8_t(std::lround((1.0 - a) * under + a * over));
    };
    p = {mix(p.r, c.r), mix(p.g, c.g), mix(p.b, c.b)};
}

void Image::paste(const Image& src, int x, int y)
{
    const int x0 = std::max(0, x), y0 = std::max(0, y);
    const int x1 = std::min(mWidth, x + src.width()), y1 = std::min(mHeight, y + src.height());
    if (x1 <= x0) return;
    for (int yy = y0; yy < y1; ++yy) std::copy_n(&src.at(x0 - x, yy - y), x1 - x0, &at(x0, yy));
}

void Image::fill(int x0, int y0, int x1, int y1, Rgb c)
{
    x0 = std::max(0, x0), y0 = std::max(0, y0);
    x1 = std::min(mWidth, x1), y1 = std::min(mHeight, y1);
    for (int yy = y0; yy < y1; ++yy) {
        for (int xx = x0; xx < x1; ++xx) at(xx, yy) = c;
    }
}

} // namespace voxhap::render
