// SPDX-License-Identifier: Apache-2.0
/// @file RenderFixtures.h
/// @brief Phantoms for the view tests: a small bright sphere off the centre of
/// an asymmetric box (so that a mirrored or transposed view cannot pass), and
/// the closed-form pixel of a world point in each view under the radiological
/// convention, computed from the volume's bounds without the code under test.
#pragma once

#include "phantoms/Phantoms.h"
#include "phantoms/Rasterize.h"
#include "render/raster/Image.h"

#include <gtest/gtest.h>

#include <cmath>

namespace voxhap::test {

/// A sphere of @p core tissue (a cortical-bone core inside shells when @p graded)
/// in fat, in an asymmetric box; air outside.
struct SpherePhantom {
    Vec3d centre{8.0, -12.0, 5.0}; ///< [mm, LPS]
    double radius = 6.0;           ///< [mm]
    volume::WorldBox box{Vec3d(-30, -40, -25), Vec3d(20, 10, 35)};
    bool graded = false; ///< cortical core r/3, cancellous to 2r/3, aorta to r: a peak at the centre

    volume::Volume make(const volume::GridSpec& grid) const
    {
        const auto& table = volume::TissueTable::builtin();
        const int fat = table.at("fat").id, cortical = table.at("cortical_bone").id;
        const int cancellous = table.at("cancellous_bone").id, aorta = table.at("aorta").id;
        const Vec3d c = centre;
        const double r = radius;
        const bool g = graded;
        const volume::Classifier classify = [=](const Vec3d& w) {
            const double d = (w - c).norm();
            if (!g) return d < r ? cortical : fat;
            return d < r / 3.0 ? cortical : d < 2.0 * r / 3.0 ? cancellous : d < r ? aorta : fat;
        };
        return volume::rasterize(classify, box, grid, table);
    }
};

/// The pixel (x right, y down, centres at integers) of world point @p p in a view
/// of @p pixelMm pixels whose field of view is the box [@p lo, @p hi]:
/// axial from the feet (x = L, y = P), coronal and 3D from the front (x = L, y = I),
/// sagittal from the patient's left (x = P, y = I).
inline render::Vec2d expectedPixel(
    const std::string& view, const Vec3d& p, const Vec3d& lo, const Vec3d& hi, double pixelMm)
{
    const auto at = [&](double fromEdgeMm) { return fromEdgeMm / pixelMm - 0.5; };
    if (view == "axial") return {at(p.x() - lo.x()), at(p.y() - lo.y())};
    if (view == "sagittal") return {at(p.y() - lo.y()), at(hi.z() - p.z())};
    return {at(p.x() - lo.x()), at(hi.z() - p.z())}; // coronal, 3d
}

/// Centroid of the pixels for which @p keep is true; NaN if none.
template <typename Keep> render::Vec2d centroid(const render::Image& img, Keep&& keep)
{
    double sx = 0, sy = 0, n = 0;
    for (int y = 0; y < img.height(); ++y) {
        for (int x = 0; x < img.width(); ++x) {
            if (keep(img.at(x, y))) sx += x, sy += y, n += 1;
        }
    }
    return n > 0 ? render::Vec2d(sx / n, sy / n) : render::Vec2d(std::nan(""), std::nan(""));
}

/// Standard deviation of the grey (channel mean) over the image: 0 for a blank image.
inline double greySpread(const render::Image& img)
{
    double s = 0, s2 = 0;
    const double n = double(img.width()) * img.height();
    for (int y = 0; y < img.height(); ++y) {
        for (int x = 0; x < img.width(); ++x) {
            const auto& p = img.at(x, y);
            const double g = (p.r + p.g + p.b) / 3.0;
            s += g, s2 += g * g;
        }
    }
    return std::sqrt(std::max(0.0, s2 / n - (s / n) * (s / n)));
}

} // namespace voxhap::test
