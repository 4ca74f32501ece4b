// SPDX-License-Identifier: Apache-2.0
/// @file TestFusionViews.cpp
/// @brief The views that check a registration (render/slices/FusionViews.h), each
/// against a property of its inputs: the checkerboard's MR tiles show the MR
/// and its CT tiles the CT; the bone edges appear where the CT has bone and
/// nowhere on a CT without it.

#include "phantoms/Phantoms.h"
#include "render/slices/FusionViews.h"
#include "volume/Grids.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

namespace voxhap::render {
namespace {

using volume::Channel;

constexpr Rgb kEdgeYellow{255, 220, 0}; // FusionViews.cpp: the bone edges' colour

volume::Volume phantom(const std::string& kind)
{
    const auto& table = volume::TissueTable::builtin();
    volume::PhantomSpec spec;
    spec.kind = kind;
    volume::GridSpec grid;
    grid.spacing = Vec3d(1, 1, 1);
    return volume::makePhantom(volume::phantomModel(spec, table), grid, table);
}

/// The volume's hu grid alone: the CT.
volume::Volume ctOf(const volume::Volume& v)
{
    volume::Volume ct(v.geometry(), v.indexBox());
    ct.setGrid(Channel::Hu, std::const_pointer_cast<openvdb::GridBase>(v.grid(Channel::Hu)));
    return ct;
}

/// An MR of uniform intensity over @p v's box: every MR pixel one grey.
volume::Volume uniformMr(const volume::Volume& v)
{
    volume::Volume mr(v.geometry(), v.indexBox());
    auto g = volume::FloatGrid::create(0.0f);
    const auto& b = v.indexBox();
    g->fill(openvdb::CoordBBox(
                openvdb::Coord(b.min.x(), b.min.y(), b.min.z()), openvdb::Coord(b.max.x(), b.max.y(), b.max.z())),
        500.0f, true);
    mr.setGrid(Channel::Intensity, g);
    return mr;
}

int count(const Image& img, const Rgb& c)
{
    int n = 0;
    for (int y = 0; y < img.height(); ++y)
        for (int x = 0; x < img.width(); ++x) n += img.at(x, y) == c;
    return n;
}

TEST(FusionViews, TheCheckerboardAlternatesMrAndCtTiles)
{
    const volume::Volume v = phantom("lumbar");
    const volume::Volume ct = ctOf(v), mr = uniformMr(v);
    FusionViewStyle style;
    style.pixelMm = 1.0;
    const FusionPanels p = renderFusionPanels(ct, mr, ViewKind::Axial, Vec3d(0, -40, 0), style);
    const double tilePx = style.checkerMm / style.pixelMm;
    std::set<std::tuple<int, int, int>> mrGreys, ctGreys;
    for (int y = 0; y < p.checkerboard.height(); ++y) {
        for (int x = 0; x < p.checkerboard.width(); ++x) {
            const bool mrTile = (int(std::floor(x / tilePx)) + int(std::floor(y / tilePx))) % 2 != 0;
            const Rgb c = p.checkerboard.at(x, y);
            (mrTile ? mrGreys : ctGreys).insert({c.r, c.g, c.b});
        }
    }
    // The uniform MR gives its tiles one grey; the CT's tiles show skin, fat,
    // muscle, bone and air: many greys (the control that the tiles differ).
    EXPECT_EQ(mrGreys.size(), 1u);
    EXPECT_GT(ctGreys.size(), 5u);
}

TEST(FusionViews, BoneEdgesAppearWhereTheCtHasBoneAndNowhereElse)
{
    FusionViewStyle style;
    style.pixelMm = 1.0;
    // The lumbar phantom's vertebrae (cortical and cancellous bone above 300 HU).
    const volume::Volume lumbar = phantom("lumbar");
    const FusionPanels withBone =
        renderFusionPanels(ctOf(lumbar), uniformMr(lumbar), ViewKind::Axial, Vec3d(0, -60, 0), style);
    EXPECT_GT(count(withBone.boneEdges, kEdgeYellow), 50);
    // Control: the slab (skin, fat, muscle) has no bone: no edge at all.
    const volume::Volume slab = phantom("slab");
    const FusionPanels noBone =
        renderFusionPanels(ctOf(slab), uniformMr(slab), ViewKind::Axial, Vec3d(0, -10, 0), style);
    EXPECT_EQ(count(noBone.boneEdges, kEdgeYellow), 0);
    EXPECT_EQ(count(withBone.checkerboard, kEdgeYellow), 0) << "edges only in their own panel";
}

} // namespace
} // namespace voxhap::render
