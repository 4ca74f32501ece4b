// SPDX-License-Identifier: Apache-2.0
/// @file TestSlices.cpp
/// @brief The GL-free slice path: sizes, where a known phantom point lands in
/// each view (closed form from the volume's bounds), window, label colours,
/// orientation letters read back from the pixels, path overlays, and that a
/// request builds only what it names from one copy of the volume.

#include "RenderFixtures.h"

#include "common/BuiltinTable.h"
#include "common/TempDirTest.h"

#include "core/Errors.h"
#include "render/outputs/Snapshot.h"
#include "render/raster/BitmapFont.h"
#include "render/raster/Draw.h"
#include "render/raster/ImageFile.h"
#include "render/slices/SliceView.h"
#include "render/views/Overlays.h"
#include "render/views/RenderVolume.h"

#include <Eigen/Geometry>

#include <cstdlib>

namespace voxhap::render {
namespace {

using test::expectedPixel;
using test::SpherePhantom;

using voxhap::test::table;

/// A bright sphere's centroid in a slice through its centre: the voxelised
/// sphere is symmetric about its centre on the axis-aligned 1 mm lattice (the
/// centre sits on a voxel corner), so only the linear resampling and the grey
/// threshold can move it, by well under half a pixel.
constexpr double kCentroidAlignedPx = 0.5;
/// On a rotated, anisotropic lattice the voxelised sphere loses that symmetry:
/// its centroid may move by up to half the largest voxel (1.5 mm here, 1.5 px).
constexpr double kCentroidObliquePx = 1.5;
/// Pixels a one-pixel line may be from its ideal position: the line is drawn at
/// the nearest pixel, so a rounding half pixel, plus the neighbour a quarter-pixel
/// sample can reach.
constexpr int kLineReachPx = 1;

/// Grey threshold between fat (−100 HU) and bone (1850 HU) in the bone window.
bool bright(const Rgb& p) { return p.r > 200 && p.r == p.g && p.g == p.b; }

void expectCentroidAt(const Image& img, const Vec2d& expected, double tol, const std::string& what)
{
    const Vec2d c = test::centroid(img, bright);
    ASSERT_TRUE(c.allFinite()) << what << ": no bright pixel";
    EXPECT_NEAR(c.x(), expected.x(), tol) << what;
    EXPECT_NEAR(c.y(), expected.y(), tol) << what;
}

class Slices : public testing::Test {
protected:
    void SetUp() override
    {
        volume::GridSpec grid;
        grid.spacing = Vec3d(1.0, 1.0, 1.0);
        mVolume = std::make_unique<volume::Volume>(mPhantom.make(grid));
        mRender = std::make_unique<RenderVolume>(*mVolume, true);
        const auto b = mVolume->worldBounds();
        mBox = {b[0], b[1]};
    }
    SliceStyle boneWindow(bool labels = false) const
    {
        SliceStyle s;
        s.window = windowLevel(WindowPreset::Bone);
        s.labels = labels;
        return s;
    }
    SpherePhantom mPhantom;
    std::unique_ptr<volume::Volume> mVolume;
    std::unique_ptr<RenderVolume> mRender;
    WorldBounds mBox;
};

TEST_F(Slices, SizeFollowsTheBoundsAndThePixel)
{
    // The box is 50 × 50 × 60 mm (x, y, z).
    const double px = 0.5;
    const ViewFrame axial = viewFrame(ViewKind::Axial, mBox, mPhantom.centre, px);
    const ViewFrame sagittal = viewFrame(ViewKind::Sagittal, mBox, mPhantom.centre, px);
    const ViewFrame coronal = viewFrame(ViewKind::Coronal, mBox, mPhantom.centre, px);
    EXPECT_EQ(axial.width, 100);
    EXPECT_EQ(axial.height, 100);
    EXPECT_EQ(sagittal.width, 100);
    EXPECT_EQ(sagittal.height, 120);
    EXPECT_EQ(coronal.width, 100);
    EXPECT_EQ(coronal.height, 120);
    const Image img = renderSlice(*mRender, coronal, boneWindow(), table());
    EXPECT_EQ(img.width(), 100);
    EXPECT_EQ(img.height(), 120);
    EXPECT_GT(test::greySpread(img), 10.0) << "not blank";
    // A pixel cap coarsens the pixel instead of cropping.
    const ViewFrame capped = viewFrame(ViewKind::Coronal, mBox, mPhantom.centre, px, 60);
    EXPECT_EQ(capped.height, 60);
    EXPECT_DOUBLE_EQ(capped.pixelMm, 1.0);
}

TEST_F(Slices, PhantomPointAtItsPixelInEachView)
{
    const double px = 1.0;
    for (const char* name : {"axial", "sagittal", "coronal"}) {
        const ViewKind kind = parseViews(name).front();
        const ViewFrame f = viewFrame(kind, mBox, mPhantom.centre, px);
        const Image img = renderSlice(*mRender, f, boneWindow(), table());
        expectCentroidAt(img, expectedPixel(name, mPhantom.centre, mBox.min, mBox.max, px), kCentroidAlignedPx, name);
        // The frame's own mapping agrees with the closed form.
        const Vec2d mapped = f.toPixel(mPhantom.centre);
        const Vec2d closed = expectedPixel(name, mPhantom.centre, mBox.min, mBox.max, px);
        EXPECT_NEAR((mapped - closed).norm(), 0.0, 1e-9) << name;
    }
}

TEST_F(Slices, ObliqueAnisotropicVolumeKeepsWorldPositions)
{
    volume::GridSpec grid;
    grid.spacing = Vec3d(0.8, 1.0, 1.5);
    grid.direction =
        (Eigen::AngleAxisd(degToRad(20.0), Vec3d::UnitZ()) * Eigen::AngleAxisd(degToRad(10.0), Vec3d::UnitX()))
            .toRotationMatrix();
    const volume::Volume v = mPhantom.make(grid);
    const RenderVolume rv(v, false);
    // The same field of view as the aligned volume, so that the closed form is unchanged.
    const double px = 1.0;
    for (const char* name : {"axial", "sagittal", "coronal"}) {
        const ViewFrame f = viewFrame(parseViews(name).front(), mBox, mPhantom.centre, px);
        const Image img = renderSlice(rv, f, boneWindow(), table());
        expectCentroidAt(img, expectedPixel(name, mPhantom.centre, mBox.min, mBox.max, px), kCentroidObliquePx, name);
    }
}

TEST_F(Slices, WindowMapsLevelToMidGrey)
{
    const WindowLevel w = windowLevel(WindowPreset::SoftTissue); // W 400, L 40
    EXPECT_EQ(windowed(40.0, w), 128);                           // 0.5 · 255 = 127.5, rounded half away from zero
    EXPECT_EQ(windowed(-160.0, w), 0);                           // level − width/2
    EXPECT_EQ(windowed(240.0, w), 255);                          // level + width/2
    EXPECT_EQ(windowed(-1000.0, w), 0);
    EXPECT_EQ(windowed(1850.0, w), 255);
}

TEST_F(Slices, LabelsBlendTheTissueColour)
{
    // A field of view 5 mm wider than the volume on each side: air around it.
    const WorldBounds wider{mBox.min - Vec3d::Constant(5.0), mBox.max + Vec3d::Constant(5.0)};
    const ViewFrame f = viewFrame(ViewKind::Axial, wider, mPhantom.centre, 1.0);
    SliceStyle s = boneWindow(true);
    const Image img = renderSlice(*mRender, f, s, table());
    const Vec2d c = expectedPixel("axial", mPhantom.centre, wider.min, wider.max, 1.0);
    // Inside the sphere: cortical bone, white through the bone window
    // ((1850 − (400 − 900)) / 1800 > 1), mixed with the bone colour.
    const auto& bone = table().at("cortical_bone").colour;
    const Rgb got = img.at(int(std::lround(c.x())), int(std::lround(c.y())));
    const auto mix = [&](double grey, int colour) {
        return std::lround((1 - s.labelOpacity) * grey + s.labelOpacity * colour);
    };
    EXPECT_EQ(got.r, mix(255, bone[0]));
    EXPECT_EQ(got.g, mix(255, bone[1]));
    EXPECT_EQ(got.b, mix(255, bone[2]));
    // Fat inside the box: its grey through the bone window, 255 · (−100 + 500) / 1800
    // = 56.7 → 57, mixed with the fat colour.
    const auto& fat = table().at("fat").colour;
    EXPECT_EQ(img.at(6, 6),
        (Rgb{std::uint8_t(mix(57, fat[0])), std::uint8_t(mix(57, fat[1])), std::uint8_t(mix(57, fat[2]))}));
    // Outside the volume (air, label 0): black, no colour.
    EXPECT_EQ(img.at(2, 2), Rgb{});
}

/// The glyph drawn in @p colour inside the region [x0, x1) × [y0, y1), read back
/// by sampling its bounding box on the 5 × 7 font grid; '?' if none matches.
char readGlyph(const Image& img, int x0, int y0, int x1, int y1, Rgb colour)
{
    int bx0 = x1, by0 = y1, bx1 = -1, by1 = -1;
    for (int y = y0; y < y1; ++y) {
        for (int x = x0; x < x1; ++x) {
            if (img.at(x, y) == colour)
                bx0 = std::min(bx0, x), by0 = std::min(by0, y), bx1 = std::max(bx1, x), by1 = std::max(by1, y);
        }
    }
    if (bx1 < 0) return '?';
    const int scale = (by1 - by0 + 1) / kGlyphHeight;
    if (scale < 1) return '?';
    for (const char candidate : std::string("APLRSI")) {
        const auto rows = glyphRows(candidate);
        // Align on the glyph's own leftmost lit column.
        int firstCol = kGlyphWidth;
        for (const auto r : rows) {
            for (int c = 0; c < kGlyphWidth; ++c) {
                if (r & (0b10000 >> c)) firstCol = std::min(firstCol, c);
            }
        }
        bool same = true;
        for (int r = 0; r < kGlyphHeight && same; ++r) {
            for (int c = 0; c < kGlyphWidth && same; ++c) {
                const int x = bx0 + (c - firstCol) * scale + scale / 2, y = by0 + r * scale + scale / 2;
                const bool lit = x >= x0 && x < x1 && img.at(x, y) == colour;
                same = lit == bool(rows[std::size_t(r)] & (0b10000 >> c));
            }
        }
        if (same) return candidate;
    }
    return '?';
}

TEST_F(Slices, OrientationLettersOnTheRadiologicalSides)
{
    // Stated convention: axial from the feet (R | L, A over P), coronal from the
    // front (R | L, S over I), sagittal from the patient's left (A | P, S over I).
    const struct {
        const char* view;
        const char* letters; // left, right, top, bottom
    } cases[] = {{"axial", "RLAP"}, {"coronal", "RLSI"}, {"sagittal", "APSI"}};
    const OverlayStyle style;
    for (const auto& c : cases) {
        const ViewFrame f = viewFrame(parseViews(c.view).front(), mBox, mPhantom.centre, 0.25); // 200+ px a side
        Image img(f.width, f.height);
        Overlays o;
        o.scaleBar = false;
        drawAnnotations(img, f, o, style);
        const int w = img.width(), h = img.height(), q = std::min(w, h) / 4;
        const std::string got{readGlyph(img, 0, h / 2 - q / 2, q, h / 2 + q / 2, style.letters),
            readGlyph(img, w - q, h / 2 - q / 2, w, h / 2 + q / 2, style.letters),
            readGlyph(img, w / 2 - q / 2, 0, w / 2 + q / 2, q, style.letters),
            readGlyph(img, w / 2 - q / 2, h - q, w / 2 + q / 2, h, style.letters)};
        EXPECT_EQ(got, c.letters) << c.view;
    }
}

TEST_F(Slices, PathOverlayThroughEntryAndTargetPixels)
{
    const double px = 0.5;
    const OverlayStyle style;
    // One path in the axial plane of the sphere's centre, one crossing it obliquely.
    planning::PlannedPath inPlane{"in plane", Vec3d(-20, -35, mPhantom.centre.z()), mPhantom.centre, std::nullopt};
    planning::PlannedPath oblique{"oblique", Vec3d(15, 5, 25), Vec3d(-10, -30, -15), std::nullopt};
    for (const planning::PlannedPath& path : {inPlane, oblique}) {
        for (const char* name : {"axial", "sagittal", "coronal"}) {
            const ViewFrame f = viewFrame(parseViews(name).front(), mBox, mPhantom.centre, px);
            Image img(f.width, f.height);
            Overlays o;
            o.paths = {path};
            o.letters = o.scaleBar = false;
            drawSliceOverlays(img, f, o, style);
            for (const Vec3d& p : {path.entry, path.target}) {
                const Vec2d e = expectedPixel(name, p, mBox.min, mBox.max, px);
                bool found = false;
                for (int dy = -kLineReachPx; dy <= kLineReachPx; ++dy) {
                    for (int dx = -kLineReachPx; dx <= kLineReachPx; ++dx) {
                        const int x = int(std::lround(e.x())) + dx, y = int(std::lround(e.y())) + dy;
                        found = found || (img.contains(x, y) && img.at(x, y) == style.path);
                    }
                }
                EXPECT_TRUE(found) << path.name << " in " << name << ": no path pixel at " << e.transpose();
            }
        }
    }
}

// A bending needle (physics.md §9) is drawn along its shaft, not along the chord
// from its hub to its tip: a needle pixel at the bent shaft's middle vertex and
// none at the chord's middle; the straight pose (control) the other way round.
TEST_F(Slices, BentNeedleIsDrawnAlongItsShaft)
{
    const double px = 0.5, z = mPhantom.centre.z();
    const OverlayStyle style;
    const Vec3d hub(-30, -20, z), mid(0, -10, z), tip(30, -20, z);
    planning::NeedlePose bent{tip, Vec3d(1, 0, 0), 60.0};
    bent.shaft = {hub, mid, tip};
    const planning::NeedlePose straight{tip, Vec3d(1, 0, 0), 60.0};
    const ViewFrame f = viewFrame(parseViews("axial").front(), mBox, mPhantom.centre, px);
    const auto needleNear = [&](const planning::NeedlePose& pose, const Vec3d& p) {
        Image img(f.width, f.height);
        Overlays o;
        o.needle = pose;
        o.letters = o.scaleBar = false;
        drawSliceOverlays(img, f, o, style);
        const Vec2d e = expectedPixel("axial", p, mBox.min, mBox.max, px);
        for (int dy = -kLineReachPx; dy <= kLineReachPx; ++dy) {
            for (int dx = -kLineReachPx; dx <= kLineReachPx; ++dx) {
                const int x = int(std::lround(e.x())) + dx, y = int(std::lround(e.y())) + dy;
                if (img.contains(x, y) && img.at(x, y) == style.needle) return true;
            }
        }
        return false;
    };
    const Vec3d chordMid = 0.5 * (hub + tip);
    EXPECT_TRUE(needleNear(bent, mid));
    EXPECT_FALSE(needleNear(bent, chordMid));
    EXPECT_TRUE(needleNear(straight, chordMid));
    EXPECT_FALSE(needleNear(straight, mid));
}

TEST_F(Slices, DashedLinesKeepBothEnds)
{
    Image img(200, 50);
    const Stroke s{Rgb{255, 0, 0}, 1.0, 6.0, 1.0};
    drawLine(img, Vec2d(3.0, 20.0), Vec2d(187.0, 20.0), s);
    EXPECT_EQ(img.at(3, 20), s.colour);
    EXPECT_EQ(img.at(187, 20), s.colour);
    int lit = 0;
    for (int x = 3; x <= 187; ++x) lit += img.at(x, 20) == s.colour;
    EXPECT_GT(lit, 70); // about half of 185 px, in dashes of 6
    EXPECT_LT(lit, 115);
}

TEST_F(Slices, ScaleBarIsARoundLengthUnderAQuarter)
{
    EXPECT_DOUBLE_EQ(scaleBarLengthMm(360.0), 50.0);
    EXPECT_DOUBLE_EQ(scaleBarLengthMm(100.0), 20.0);
    EXPECT_DOUBLE_EQ(scaleBarLengthMm(40.0), 10.0);
    EXPECT_DOUBLE_EQ(scaleBarLengthMm(8.0), 2.0);
}

TEST_F(Slices, RequestBuildsOnlyWhatItNames)
{
    // Slices only, no labels: one float copy of the volume, no label array,
    // and no display needed (this test runs with none).
    RenderRequest r;
    r.views = {ViewKind::Axial, ViewKind::Coronal};
    r.labels = false;
    Snapshot only(*mVolume, r, table());
    const auto voxels = std::size_t(mVolume->indexBox().voxelCount());
    EXPECT_FALSE(only.volume().hasLabels());
    EXPECT_EQ(only.volume().denseBytes() / voxels, sizeof(float));
    EXPECT_THROW(only.frame(ViewKind::Sagittal), ValueError);
    EXPECT_THROW(only.render(ViewKind::ThreeD), ValueError);
    const Image a = only.render(ViewKind::Axial);
    EXPECT_EQ(a.width(), only.frame(ViewKind::Axial).width);
    // With labels: one short per voxel more, shared by every view.
    r.labels = true;
    r.views = {ViewKind::Axial, ViewKind::Sagittal, ViewKind::Coronal};
    Snapshot all(*mVolume, r, table());
    EXPECT_TRUE(all.volume().hasLabels());
    EXPECT_EQ(all.volume().denseBytes() / voxels, sizeof(float) + sizeof(short));
}

TEST_F(Slices, PointDefaultsToThePathTarget)
{
    RenderRequest r;
    r.views = {ViewKind::Axial};
    r.plan.paths = {planning::PlannedPath{"p", Vec3d(0, 5, 0), Vec3d(1, -20, 3), std::nullopt}};
    Snapshot s(*mVolume, r, table());
    EXPECT_EQ(s.point(), Vec3d(1, -20, 3));
    r.plan.paths.clear();
    Snapshot c(*mVolume, r, table());
    EXPECT_EQ(c.point(), 0.5 * (mBox.min + mBox.max));
}

TEST(ContactSheet, TwoByTwoInRequestOrder)
{
    const Image a(40, 30, Rgb{255, 0, 0}), b(20, 50, Rgb{0, 255, 0}), c(40, 50, Rgb{0, 0, 255}),
        d(10, 10, Rgb{9, 9, 9});
    const Image sheet = contactSheet({a, b, c, d});
    // Cells of 40 × 50 with a 4 px gap.
    EXPECT_EQ(sheet.width(), 84);
    EXPECT_EQ(sheet.height(), 104);
    EXPECT_EQ(sheet.at(20, 25), a.at(0, 0));      // top left
    EXPECT_EQ(sheet.at(44 + 20, 25), b.at(0, 0)); // top right
    EXPECT_EQ(sheet.at(20, 54 + 25), c.at(0, 0)); // bottom left
    EXPECT_EQ(sheet.at(44 + 20, 54 + 25), d.at(0, 0));
}

class PngFiles : public test::TempDirTest { };

TEST_F(PngFiles, RoundTripAndNoPartialFile)
{
    Image img(7, 5, Rgb{1, 2, 3});
    img.at(6, 4) = {250, 128, 0};
    const auto file = mDir / "x.png";
    writePng(img, file);
    const Image back = readImage(file);
    ASSERT_EQ(back.width(), 7);
    ASSERT_EQ(back.height(), 5);
    EXPECT_EQ(back.at(0, 0), img.at(0, 0));
    EXPECT_EQ(back.at(6, 4), img.at(6, 4));
    // An unwritable place: one error naming the file, nothing left behind.
    const auto bad = mDir / "missing-dir" / "y.png";
    EXPECT_THROW(writePng(img, bad), IoError);
    EXPECT_FALSE(std::filesystem::exists(bad.parent_path()));
}

} // namespace
} // namespace voxhap::render
