// SPDX-License-Identifier: Apache-2.0
/// @file SliceView.cpp
#include "render/slices/SliceView.h"

#include "render/views/RenderVolume.h"
#include "volume/TissueTable.h"

#include <algorithm>
#include <cmath>

namespace voxhap::render {

std::uint8_t windowed(double value, const WindowLevel& w)
{
    const double t = (value - (w.level - 0.5 * w.width)) / w.width;
    return std::uint8_t(std::lround(255.0 * std::clamp(t, 0.0, 1.0)));
}

Image renderSlice(const RenderVolume& v, const ViewFrame& f, const SliceStyle& style, const volume::TissueTable& table)
{
    const std::vector<float> values = v.sliceValues(f);
    Image img(f.width, f.height);
    for (int y = 0; y < f.height; ++y) {
        for (int x = 0; x < f.width; ++x) {
            const std::uint8_t g =
                windowed(values[std::size_t(y) * std::size_t(f.width) + std::size_t(x)], style.window);
            img.at(x, y) = {g, g, g};
        }
    }
    if (!style.labels || !v.hasLabels() || style.labelOpacity <= 0.0) return img;
    // Tissue colours by id; ids the table does not know stay uncoloured.
    std::vector<const volume::Tissue*> byId(std::size_t(table.maxId()) + 1, nullptr);
    for (const volume::Tissue& t : table.tissues()) byId[std::size_t(t.id)] = &t;
    const std::vector<std::int32_t> ids = v.sliceLabels(f);
    for (int y = 0; y < f.height; ++y) {
        for (int x = 0; x < f.width; ++x) {
            const std::int32_t id = ids[std::size_t(y) * std::size_t(f.width) + std::size_t(x)];
            if (id <= 0 || id > table.maxId() || !byId[std::size_t(id)]) continue;
            const auto& c = byId[std::size_t(id)]->colour;
            img.blend(x, y, Rgb{c[0], c[1], c[2]}, style.labelOpacity);
        }
    }
    return img;
}

} // namespace voxhap::render
