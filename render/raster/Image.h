// SPDX-License-Identifier: Apache-2.0
/// @file Image.h
/// @brief An 8-bit RGB raster, rows from the top: what every view renders
/// into, what overlays draw on and what the PNG writer takes.
///
/// Kept free of VTK and OpenImageIO so that slices, overlays and the contact
/// sheet can be made and tested without a display or an image library.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace voxhap::render {

/// @brief A position in an image, in pixels: x to the right, y down; pixel
/// centres sit at integer coordinates.
using Vec2d = Eigen::Vector2d;

/// @brief An sRGB colour, 0..255 per channel.
struct Rgb {
    std::uint8_t r = 0, g = 0, b = 0;
    bool operator==(const Rgb&) const = default;
};
static_assert(sizeof(Rgb) == 3, "Image::data() hands out packed RGB triplets");

class Image {
public:
    Image() = default;
    Image(int width, int height, Rgb fill = {});

    int width() const { return mWidth; }
    int height() const { return mHeight; }
    bool empty() const { return mWidth == 0 || mHeight == 0; }
    bool contains(int x, int y) const { return x >= 0 && y >= 0 && x < mWidth && y < mHeight; }

    Rgb& at(int x, int y) { return mPixels[std::size_t(y) * std::size_t(mWidth) + std::size_t(x)]; }
    const Rgb& at(int x, int y) const { return mPixels[std::size_t(y) * std::size_t(mWidth) + std::size_t(x)]; }
    /// @brief Packed RGB bytes, row by row from the top (what PNG writers expect).
    const std::uint8_t* data() const { return reinterpret_cast<const std::uint8_t*>(mPixels.data()); }
    std::uint8_t* data() { return reinterpret_cast<std::uint8_t*>(mPixels.data()); }

    /// @brief Set a pixel if it lies inside the image (drawing clips silently).
    void put(int x, int y, Rgb c)
    {
        if (contains(x, y)) at(x, y) = c;
    }
    /// @brief Mix @p c over a pixel with opacity @p alpha in [0, 1], if inside.
    void blend(int x, int y, Rgb c, double alpha);
    /// @brief Copy @p src with its top-left corner at (@p x, @p y), clipped.
    void paste(const Image& src, int x, int y);
    /// @brief Fill the rectangle [x0, x1) × [y0, y1), clipped.
    void fill(int x0, int y0, int x1, int y1, Rgb c);

private:
    int mWidth = 0, mHeight = 0;
    std::vector<Rgb> mPixels;
};

} // namespace voxhap::render
