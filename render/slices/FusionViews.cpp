// SPDX-License-Identifier: Apache-2.0
/// @file FusionViews.cpp
/// @brief Checkerboard, bone edges and colour overlay from two slices of one frame.

#include "render/slices/FusionViews.h"

#include "core/Errors.h"
#include "render/raster/Draw.h"
#include "render/slices/SliceView.h"
#include "render/views/RenderVolume.h"
#include "render/views/ViewFrame.h"
#include "volume/Volume.h"

#include <algorithm>
#include <cmath>

namespace voxhap::render {

namespace {

constexpr Rgb kEdge{255, 220, 0}; // the CT's bone edges: yellow over grey

/// A volume holding only channel @p c of @p v (the grid is shared, not copied).
volume::Volume only(const volume::Volume& v, volume::Channel c)
{
    volume::Volume out(v.transformPtr()->copy(), v.indexBox());
    out.setGrid(c, std::const_pointer_cast<openvdb::GridBase>(v.grid(c)));
    out.metadata() = v.metadata();
    return out;
}

/// The "hot" colour map: black, red, yellow, white.
Rgb hot(double t)
{
    t = std::clamp(t, 0.0, 1.0);
    const auto c = [](double x) { return std::uint8_t(std::lround(255.0 * std::clamp(x, 0.0, 1.0))); };
    return {c(3.0 * t), c(3.0 * t - 1.0), c(3.0 * t - 2.0)};
}

Image grey(const std::vector<float>& values, const ViewFrame& f, const WindowLevel& w)
{
    Image img(f.width, f.height);
    for (int y = 0; y < f.height; ++y) {
        for (int x = 0; x < f.width; ++x) {
            const std::uint8_t g = windowed(values[std::size_t(y) * std::size_t(f.width) + std::size_t(x)], w);
            img.at(x, y) = {g, g, g};
        }
    }
    return img;
}

} // namespace

FusionPanels renderFusionPanels(
    const volume::Volume& ct, const volume::Volume& mr, ViewKind view, const Vec3d& point, const FusionViewStyle& style)
{
    if (!ct.has(volume::Channel::Hu)) throw ValueError("fusion views: the CT has no hu grid");
    const volume::Channel mc = mr.has(volume::Channel::T1) ? volume::Channel::T1 : volume::Channel::Intensity;
    if (!mr.has(mc)) throw ValueError("fusion views: the MR has neither a t1 nor an intensity grid");
    const RenderVolume ctView(only(ct, volume::Channel::Hu), false);
    const RenderVolume mrView(only(mr, mc), false);
    const double pixel = style.pixelMm > 0 ? style.pixelMm : ctView.finestSpacing();
    const ViewFrame f = viewFrame(view, ctView.worldBounds(), point, pixel, style.maxPixels);

    const std::vector<float> hu = ctView.sliceValues(f);
    const std::vector<float> mrValues = mrView.sliceValues(f);
    const WindowLevel ctWindow = ctView.defaultWindow();
    const WindowLevel mrWindow = mrView.defaultWindow();
    const Image ctGrey = grey(hu, f, ctWindow);
    const Image mrGrey = grey(mrValues, f, mrWindow);

    FusionPanels out;
    // Checkerboard: tiles of checkerMm alternate CT and MR, so an edge that
    // jumps at a tile border shows the misalignment.
    out.checkerboard = Image(f.width, f.height);
    const double tilePx = std::max(1.0, style.checkerMm / f.pixelMm);
    for (int y = 0; y < f.height; ++y) {
        for (int x = 0; x < f.width; ++x) {
            const bool mrTile = (int(std::floor(x / tilePx)) + int(std::floor(y / tilePx))) % 2 != 0;
            out.checkerboard.at(x, y) = mrTile ? mrGrey.at(x, y) : ctGrey.at(x, y);
        }
    }
    // The CT's bone edges over the MR: bone pixels with a neighbour below the threshold.
    out.boneEdges = mrGrey;
    auto bone = [&](int x, int y) {
        return double(hu[std::size_t(y) * std::size_t(f.width) + std::size_t(x)]) >= style.boneHu;
    };
    for (int y = 1; y + 1 < f.height; ++y) {
        for (int x = 1; x + 1 < f.width; ++x) {
            if (bone(x, y) && !(bone(x - 1, y) && bone(x + 1, y) && bone(x, y - 1) && bone(x, y + 1)))
                out.boneEdges.at(x, y) = kEdge;
        }
    }
    // The MR in colour over the CT in grey, where the MR has signal.
    out.colour = ctGrey;
    const double lo = mrWindow.level - 0.5 * mrWindow.width;
    for (int y = 0; y < f.height; ++y) {
        for (int x = 0; x < f.width; ++x) {
            const double v = mrValues[std::size_t(y) * std::size_t(f.width) + std::size_t(x)];
            if (!(v > 0.0)) continue; // the MR's background: nothing to show
            out.colour.blend(x, y, hot((v - lo) / mrWindow.width), style.colourOpacity);
        }
    }
    return out;
}

Image fusionSheet(const FusionPanels& before, const FusionPanels& after, const std::string& title)
{
    const int w = before.checkerboard.width(), h = before.checkerboard.height();
    const int scale = 1;
    const int titleH = textHeight(2) + 8, labelH = textHeight(scale) + 6, gap = 4;
    Image sheet(3 * w + 4 * gap, titleH + 2 * (labelH + h) + 3 * gap, Rgb{24, 24, 24});
    drawText(sheet, gap, 4, title, Rgb{255, 255, 255}, 2);
    const char* columns[] = {"checkerboard CT / MR", "CT bone edges over MR", "MR in colour over CT"};
    const FusionPanels* rows[] = {&before, &after};
    const char* rowNames[] = {"before: header geometry", "after: registered"};
    for (int r = 0; r < 2; ++r) {
        const int y = titleH + gap + r * (labelH + h + gap);
        const Image* panels[] = {&rows[r]->checkerboard, &rows[r]->boneEdges, &rows[r]->colour};
        for (int c = 0; c < 3; ++c) {
            const int x = gap + c * (w + gap);
            drawText(sheet, x, y, std::string(rowNames[r]) + " - " + columns[c], Rgb{230, 230, 230}, scale);
            sheet.paste(*panels[c], x, y + labelH);
        }
    }
    return sheet;
}

} // namespace voxhap::render
