// SPDX-License-Identifier: Apache-2.0
/// @file TestMrViews.cpp
/// @brief MR views (issue 27 item 10) on a synthetic MR: a body whose values
/// ramp from 100 to 800 left to right, a small artefact at 5000 and air (0,
/// inactive) around it. The default window comes from the body's own values,
/// never a CT preset, in the slices, the viewer and the 3D view; the views
/// label the unit.

#include "RenderFixtures.h"

#include "common/BuiltinTable.h"

#include "render/outputs/Snapshot.h"
#include "render/raster/Draw.h"
#include "render/viewer/Viewer.h"
#include "render/views/RenderVolume.h"
#include "render/volume3d/Display.h"
#include "volume/Grids.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace voxhap::render {
namespace {

using voxhap::test::table;

// The phantom [mm, LPS]: an elliptic cylinder along z inside a box of air, with
// room above it (anterior, the images' top rows) for the title and legend.
constexpr double kHalfX = 50.0, kHalfY = 40.0, kHalfZ = 35.0;
const volume::WorldBox kMrBox{Vec3d(-60, -70, -40), Vec3d(60, 50, 40)};
// Body values: 450 + 7 x, from 100 (right, x = −50) to 800 (left, x = 50).
constexpr double kRampLow = 100.0, kRampHigh = 800.0;
double ramp(double x) { return 0.5 * (kRampLow + kRampHigh) + x * (kRampHigh - kRampLow) / (2.0 * kHalfX); }
// An artefact of 5000 (a flow or susceptibility spike) in a 10 mm cube: 0.5 % of
// the body, which a robust range ignores and a min..max range does not.
constexpr double kSpike = 5000.0;
bool inSpike(const Vec3d& p) { return p.x() > 20 && p.x() < 30 && p.y() > -5 && p.y() < 5 && p.z() > 4 && p.z() < 14; }
bool inBody(const Vec3d& p) { return std::hypot(p.x() / kHalfX, p.y() / kHalfY) < 1.0 && std::abs(p.z()) < kHalfZ; }

/// The phantom on a 1 mm lattice in @p channel; air is the inactive background.
volume::Volume mrPhantom(volume::Channel channel)
{
    volume::Geometry g;
    g.origin = kMrBox.min;
    const Vec3i n = (kMrBox.max - kMrBox.min).cast<int>();
    volume::Volume v(g, volume::IndexBox{Vec3i::Zero(), n});
    const float air = channel == volume::Channel::Hu ? volume::kAirHu : 0.0f;
    auto grid = volume::FloatGrid::create(air);
    auto acc = grid->getAccessor();
    for (int k = 0; k <= n.z(); ++k) {
        for (int j = 0; j <= n.y(); ++j) {
            for (int i = 0; i <= n.x(); ++i) {
                const Vec3d p = v.indexToWorld(Vec3d(i, j, k));
                if (inBody(p)) acc.setValue(openvdb::Coord(i, j, k), float(inSpike(p) ? kSpike : ramp(p.x())));
            }
        }
    }
    v.setGrid(channel, grid);
    v.metadata().modality = channel == volume::Channel::Hu ? "CT" : "MR";
    return v;
}

/// The body's values sorted, read from the grid: the reference the percentiles are checked against.
std::vector<float> sortedBody(const volume::Volume& v, volume::Channel c)
{
    const auto grid = openvdb::gridConstPtrCast<volume::FloatGrid>(v.grid(c));
    std::vector<float> out;
    for (auto it = grid->cbeginValueOn(); it; ++it) out.push_back(*it);
    std::sort(out.begin(), out.end());
    return out;
}

double greyOf(const Rgb& p) { return (p.r + p.g + p.b) / 3.0; }

// A grey ramp through a window drawn from the body's own values reaches both ends
// of the grey scale within the body: its darkest pixel at most this grey, its
// brightest at least 255 minus this. The 1st and 99th percentiles of the ramp cut
// 1 % of the body at each end to black and white; 20 of 255 leaves room for the
// slice's linear interpolation at the body's edge.
constexpr double kRampEndGrey = 20.0;

TEST(MrWindow, ComesFromTheBodysPercentilesNotACtPreset)
{
    for (const volume::Channel c : {volume::Channel::T1, volume::Channel::Intensity}) {
        const volume::Volume v = mrPhantom(c);
        const RenderVolume rv(v, false);
        EXPECT_EQ(rv.channel(), c == volume::Channel::T1 ? ScalarChannel::T1 : ScalarChannel::Intensity);
        // The 1st and 99th percentiles of the active voxels, by a full sort here;
        // the renderer bins the values (65536 bins over their range): within a bin.
        const std::vector<float> body = sortedBody(v, c);
        const auto percentile = [&](double p) {
            return double(body[std::size_t(std::floor(p / 100.0 * double(body.size() - 1)))]);
        };
        const double bin = (body.back() - body.front()) / 65536.0;
        const auto [lo, hi] = rv.bodyRange();
        EXPECT_NEAR(lo, percentile(1.0), bin);
        EXPECT_NEAR(hi, percentile(99.0), bin);
        // Within the tissue's values: the air (0) and the artefact (5000) are not.
        EXPECT_GT(lo, kRampLow);
        EXPECT_LT(hi, kRampHigh);
        for (const BlendMode m : {BlendMode::Colour, BlendMode::Grey, BlendMode::Mip}) {
            const WindowLevel w = rv.defaultWindow(m);
            EXPECT_DOUBLE_EQ(w.level - 0.5 * w.width, lo) << blendModeName(m);
            EXPECT_DOUBLE_EQ(w.level + 0.5 * w.width, hi) << blendModeName(m);
            for (const WindowPreset p : {WindowPreset::SoftTissue, WindowPreset::Bone, WindowPreset::Lung}) {
                EXPECT_FALSE(w.width == windowLevel(p).width && w.level == windowLevel(p).level) << "a CT preset on MR";
            }
        }
    }
    // The presets' names, which a caller showing MR refuses; numbers in MR units stay valid.
    for (const char* name : {"bone", "soft", "soft-tissue", " lung "}) EXPECT_TRUE(namesCtPreset(name)) << name;
    EXPECT_FALSE(namesCtPreset("700,450"));
    // CT keeps its presets.
    const RenderVolume ct(mrPhantom(volume::Channel::Hu), false);
    EXPECT_EQ(ct.defaultWindow().width, windowLevel(WindowPreset::SoftTissue).width);
    EXPECT_EQ(ct.defaultWindow(BlendMode::Mip).level, windowLevel(WindowPreset::Bone).level);
}

/// An axial slice through z = 0 (away from the artefact) of the phantom in @p c,
/// 1 mm pixels; the crosshair in the air at the back left, off the rows tested.
Image axialSlice(volume::Channel c)
{
    RenderRequest r;
    r.views = {ViewKind::Axial};
    r.point = Vec3d(57, 45, 0);
    r.labels = false;
    r.pixelMm = 1.0;
    Snapshot s(mrPhantom(c), r, table());
    return s.render(ViewKind::Axial);
}

/// The pixel of world point @p p in that slice (closed form, RenderFixtures.h).
Vec2d axialPixel(const Vec3d& p)
{
    static const auto b = mrPhantom(volume::Channel::T1).worldBounds();
    return test::expectedPixel("axial", p, b[0], b[1], 1.0);
}

Rgb at(const Image& img, const Vec2d& px) { return img.at(int(std::lround(px.x())), int(std::lround(px.y()))); }

TEST(MrSlice, TheBodyFillsTheGreyRangeAndTheAirIsBlack)
{
    for (const volume::Channel c : {volume::Channel::T1, volume::Channel::Intensity}) {
        const Image img = axialSlice(c);
        // The row y = 20 mm: clear of the orientation letters (middle rows), the
        // title (top) and the scale bar (bottom). The body spans |x| < 43.3 mm there.
        constexpr double y = 20.0, halfWidth = kHalfX * 0.866;
        std::vector<double> grey;
        for (double x = -halfWidth + 2.0; x <= halfWidth - 2.0; x += 1.0) { // 2 mm in from the body's edge
            grey.push_back(greyOf(at(img, axialPixel(Vec3d(x, y, 0)))));
        }
        for (std::size_t i = 1; i < grey.size(); ++i) {
            EXPECT_GE(grey[i], grey[i - 1]) << "the ramp goes up to the left, i " << i;
        }
        EXPECT_LE(grey.front(), kRampEndGrey);
        EXPECT_GE(grey.back(), 255.0 - kRampEndGrey);
        // Air, 5 mm outside the body on the same row, on both sides.
        for (const double x : {-halfWidth - 5.0, halfWidth + 5.0}) {
            EXPECT_EQ(greyOf(at(img, axialPixel(Vec3d(x, y, 0)))), 0.0) << "x " << x;
        }
    }
}

/// White pixels in the line under the title (the legend's place): the phantom
/// leaves that corner to air, so only text can be white there.
int legendLinePixels(const Image& img)
{
    constexpr int kMarginPx = 6; // Overlays.cpp's margin
    const int scale = 1, th = textHeight(scale);
    int n = 0;
    for (int y = kMarginPx + th + 2; y < kMarginPx + 2 * th + 2; ++y) {
        for (int x = kMarginPx; x < std::min(img.width(), kMarginPx + 20 * 6); ++x)
            n += img.at(x, y) == Rgb{255, 255, 255};
    }
    return n;
}

TEST(MrSlice, TheLegendNamesTheUnit)
{
    const WindowLevel w{700.0, 450.0};
    EXPECT_EQ(windowLegend(ScalarChannel::T1, w), "T1 100..800 ms");
    EXPECT_EQ(windowLegend(ScalarChannel::Intensity, w), "MR 100..800 a.u.");
    EXPECT_EQ(windowLegend(ScalarChannel::Hu, WindowLevel{400.0, 40.0}), "CT -160..240 HU");
    ASSERT_LT(std::min(axialSlice(volume::Channel::T1).width(), axialSlice(volume::Channel::T1).height()), 400)
        << "the text scale assumed above";
    EXPECT_GT(legendLinePixels(axialSlice(volume::Channel::T1)), 0);
    EXPECT_GT(legendLinePixels(axialSlice(volume::Channel::Intensity)), 0);
    EXPECT_EQ(legendLinePixels(axialSlice(volume::Channel::Hu)), 0) << "CT's look is unchanged";
}

TEST(MrViewer, TheWKeyKeepsTheBodysWindowAndSaysWhy)
{
    const volume::Volume v = mrPhantom(volume::Channel::Intensity);
    ViewerOptions o;
    o.width = 244, o.height = 268;
    o.threeD = false;
    o.labels = false;
    Viewer viewer(v, o, table());
    const Image before = viewer.render();
    ViewerEvent w;
    w.key = "w";
    EXPECT_TRUE(viewer.handle(w));
    EXPECT_NE(viewer.status().find("CT windows do not apply to MR"), std::string::npos) << viewer.status();
    const Image after = viewer.render();
    // The panes (the status bar changed) are the same pictures.
    const PaneRect& axial = viewer.layout().pane(ViewKind::Axial);
    for (int y = axial.y; y < axial.y + axial.height; ++y) {
        for (int x = axial.x; x < axial.x + axial.width; ++x)
            ASSERT_EQ(before.at(x, y), after.at(x, y)) << x << "," << y;
    }
}

class MrView3d : public testing::Test {
protected:
    static void SetUpTestSuite() { sDisplay = new DisplayGuard(); }
    static void TearDownTestSuite()
    {
        delete sDisplay;
        sDisplay = nullptr;
    }
    void SetUp() override
    {
        if (!sDisplay->available()) GTEST_FAIL() << "no display for the 3D view: " << sDisplay->why();
    }
    static DisplayGuard* sDisplay;
};
DisplayGuard* MrView3d::sDisplay = nullptr;

TEST_F(MrView3d, TheMaximumProjectionRampsOverTheBodysRange)
{
    // From the front, along y: a pixel at (x, z) shows the largest value on its ray,
    // the ramp's ramp(x) on rows away from the artefact. Through the body's own
    // window the ramp spans the grey scale; through CT's bone window (the MIP's CT
    // default, −500..1300) it would stay between 85 and 185.
    RenderRequest r;
    r.views = {ViewKind::ThreeD};
    r.mode = BlendMode::Mip;
    r.labels = false;
    r.criticalSurfaces = false;
    r.pixelMm = 1.0;
    Snapshot s(mrPhantom(volume::Channel::T1), r, table());
    const Image img = s.render(ViewKind::ThreeD);
    const ViewFrame& f = s.frame(ViewKind::ThreeD);
    const WorldBounds b = s.volume().worldBounds();
    std::vector<double> grey;
    for (double x = -kHalfX + 3.0; x <= kHalfX - 3.0; x += 1.0) { // z = −12 mm: clear of letters and scale bar
        grey.push_back(greyOf(at(img, test::expectedPixel("3d", Vec3d(x, 0, -12.0), b.min, b.max, f.pixelMm))));
    }
    // Ray casting samples between voxels: allow a grey level of jitter [chosen].
    for (std::size_t i = 1; i < grey.size(); ++i) EXPECT_GE(grey[i], grey[i - 1] - 1.0) << "i " << i;
    EXPECT_LE(grey.front(), kRampEndGrey);
    EXPECT_GE(grey.back(), 255.0 - kRampEndGrey);
}

} // namespace
} // namespace voxhap::render
