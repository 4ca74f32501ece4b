// SPDX-License-Identifier: Apache-2.0
/// @file TestInteractive3d.cpp
/// @brief The interactive 3D pane (issue 28 item 7): the orbit camera against
/// closed-form rotations, the viewer's drag, wheel and reset driven by
/// synthetic events, and the reduced-quality path: what renders while the
/// camera moves, what after it stops, and that the moving picture still shows
/// the bone where the camera projects it. No timing here (that is
/// `voxhap bench render`'s).

#include "RenderFixtures.h"

#include "common/BuiltinTable.h"
#include "common/Prerequisites.h"
#include "common/Tolerances.h"
#include "core/Errors.h"
#include "render/viewer/OrbitCamera.h"
#include "render/viewer/Viewer.h"
#include "render/viewer/ViewerScript.h"
#include "render/views/RenderVolume.h"
#include "render/volume3d/Display.h"
#include "render/volume3d/VolumeView3d.h"

#include <chrono>
#include <cmath>
#include <numbers>
#include <utility>

namespace voxhap::render {
namespace {

using test::expectedPixel;
using test::nearVec;
using test::SpherePhantom;

/// Unit vectors turned by Eigen's angle-axis: a few roundings of numbers of
/// order 1, so 1e-12 is far above round-off and far below any visible turn.
constexpr double kCameraTol = 1e-12;

ViewFrame frontFrame(int w = 100, int h = 80)
{
    const WorldBounds box{Vec3d(-30, -40, -25), Vec3d(20, 10, 35)};
    ViewFrame f = viewFrame(ViewKind::ThreeD, box, 0.5 * (box.min + box.max), 1.0);
    const Vec3d c = f.centre();
    f.width = w, f.height = h;
    f.origin = c - f.pixelMm * (0.5 * (w - 1) * f.right + 0.5 * (h - 1) * f.down);
    return f;
}

TEST(OrbitCamera, HorizontalDragTurnsAboutTheViewUp)
{
    const ViewFrame home = frontFrame();
    OrbitCamera cam(home);
    ASSERT_TRUE(nearVec(home.normal, Vec3d(0, 1, 0), kCameraTol)) << "from the front, looking posterior";
    // 90° is 90/200 of the pane's width; dragging right turns the camera by
    // −90° about +z (VTK's Azimuth(−90)): it then looks along +x, from the
    // patient's right, with the patient's posterior on the image's left.
    cam.drag(home.width * 90.0 / kOrbitDegreesPerPane, 0.0);
    EXPECT_TRUE(nearVec(cam.frame().normal, Vec3d(1, 0, 0), kCameraTol));
    EXPECT_TRUE(nearVec(cam.frame().right, Vec3d(0, -1, 0), kCameraTol));
    EXPECT_TRUE(nearVec(cam.frame().down, home.down, kCameraTol)) << "the view up stays";
    EXPECT_TRUE(nearVec(cam.frame().centre(), home.centre(), kCameraTol)) << "it orbits the centre";
    EXPECT_EQ(cam.frame().pixelMm, home.pixelMm);
    EXPECT_FALSE(cam.atHome());
}

TEST(OrbitCamera, VerticalDragTurnsAboutTheScreenAxisAndWheelZooms)
{
    const ViewFrame home = frontFrame();
    OrbitCamera cam(home);
    // Dragging down by 90/200 of the height: Elevation(+90), the camera rises
    // over the head and looks down (−z); its view up, +z before, turns with
    // it to posterior (+y), so anterior is at the bottom of the image.
    cam.drag(0.0, home.height * 90.0 / kOrbitDegreesPerPane);
    EXPECT_TRUE(nearVec(cam.frame().normal, Vec3d(0, 0, -1), kCameraTol));
    EXPECT_TRUE(nearVec(cam.frame().down, Vec3d(0, -1, 0), kCameraTol));
    EXPECT_TRUE(nearVec(cam.frame().right, home.right, kCameraTol));
    // Two wheel steps in: the pixel shrinks by 1.21², about the same centre.
    cam.wheel(2);
    EXPECT_NEAR(cam.frame().pixelMm, home.pixelMm / (kWheelZoom * kWheelZoom), kCameraTol * home.pixelMm);
    EXPECT_TRUE(nearVec(cam.frame().centre(), home.centre(), kCameraTol));
    cam.wheel(-2);
    EXPECT_NEAR(cam.frame().pixelMm, home.pixelMm, kCameraTol * home.pixelMm);
    // Reset gives back the home frame exactly, not a frame near it.
    cam.reset();
    EXPECT_TRUE(cam.atHome());
    EXPECT_EQ(cam.frame().origin, home.origin);
    EXPECT_EQ(cam.frame().normal, home.normal);
}

TEST(ViewerScript, DragAndReleaseSteps)
{
    const auto steps = parseViewerScript("drag 3d 40 -10.5\nrelease\n", "ev.txt");
    ASSERT_EQ(steps.size(), 2u);
    EXPECT_EQ(steps[0].event.kind, ViewerEvent::Kind::Drag);
    EXPECT_EQ(steps[0].event.pane, ViewKind::ThreeD);
    EXPECT_EQ(steps[0].event.px, Vec2d(40, -10.5));
    EXPECT_EQ(steps[1].event.kind, ViewerEvent::Kind::Release);
    EXPECT_THROW(parseViewerScript("drag 3d 40\n", "ev.txt"), ValueError);
    EXPECT_THROW(parseViewerScript("release now\n", "ev.txt"), ValueError);
}

/// The reduced-quality path of VolumeView3d on a bone sphere in fat (colour mode, the viewer's default).
class Interactive3d : public testing::Test {
protected:
    static void SetUpTestSuite()
    {
        sDisplay = new DisplayGuard(); // SetUp skips or fails each test without one
    }
    static void TearDownTestSuite()
    {
        delete sDisplay;
        sDisplay = nullptr;
    }
    void SetUp() override
    {
        VOXHAP_REQUIRE(sDisplay->available(), "a display for the 3D view (xvfb): " << sDisplay->why());
        volume::GridSpec grid;
        grid.spacing = Vec3d(0.5, 0.5, 0.5);
        mVolume = std::make_unique<volume::Volume>(mPhantom.make(grid));
        const auto b = mVolume->worldBounds();
        mBox = {b[0], b[1]};
        mFrame = viewFrame(ViewKind::ThreeD, mBox, 0.5 * (mBox.min + mBox.max), 0.5);
    }
    static DisplayGuard* sDisplay;
    SpherePhantom mPhantom; // cortical bone, radius 6 mm, centre (8, −12, 5), off the box centre
    std::unique_ptr<volume::Volume> mVolume;
    WorldBounds mBox;
    ViewFrame mFrame;
};

DisplayGuard* Interactive3d::sDisplay = nullptr;

double grey(const Rgb& p) { return (p.r + p.g + p.b) / 3.0; }

/// Mean grey of the 3 × 3 pixels around @p at.
double greyAround(const Image& img, const Vec2d& at)
{
    double s = 0;
    int n = 0;
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            const int x = int(std::lround(at.x())) + dx, y = int(std::lround(at.y())) + dy;
            if (img.contains(x, y)) s += grey(img.at(x, y)), ++n;
        }
    }
    return n ? s / n : 0.0;
}

double meanGreyDifference(const Image& a, const Image& b)
{
    double s = 0;
    for (int y = 0; y < a.height(); ++y) {
        for (int x = 0; x < a.width(); ++x) s += std::abs(grey(a.at(x, y)) - grey(b.at(x, y)));
    }
    return s / (double(a.width()) * a.height());
}

long differingPixels(const Image& a, const Image& b)
{
    long n = 0;
    for (int y = 0; y < a.height(); ++y) {
        for (int x = 0; x < a.width(); ++x) n += !(a.at(x, y) == b.at(x, y));
    }
    return n;
}

/// The moving picture against the full one, mean |grey| over the image: the
/// bone sphere's rim and the box's edges move by up to a reduced pixel (3 px
/// at the default factor) and nearest-voxel steps band the shading.
/// `voxhap bench render` measures 1.6 (torso phantom) to 4.9 (CT) grey levels
/// for the default path; 12 (5 % of the range) leaves room for that and still
/// fails a frame that misses the sphere or draws the box elsewhere (tens).
constexpr double kMovingMeanGrey = 12.0;
/// The bone sphere's projected centre is bright at both qualities: cortical
/// bone (table colour 255, 255, 240) at 0.3 opacity per mm over a 12 mm chord
/// saturates; fat around it (250, 220, 120 at 0.004 per mm) stays far below.
/// The centre must be at least this much greyer than the fat beside the sphere.
constexpr double kBoneOverFatGrey = 40.0;

TEST_F(Interactive3d, MovingFramesAreReducedAndShowTheBoneWhereTheCameraPutsIt)
{
    const RenderVolume rv(*mVolume, false);
    for (const MovingPath path : {MovingPath::Subsample, MovingPath::Shrunk}) {
        SCOPED_TRACE(path == MovingPath::Subsample ? "subsample" : "shrunk");
        View3dStyle style;
        style.moving = path;
        Overlays none;
        none.letters = false, none.scaleBar = false;
        VolumeView3d view(rv, mFrame, style, volume::TissueTable::builtin(), none);
        const Image full = view.render(RenderQuality::Full);
        EXPECT_EQ(view.lastQuality(), RenderQuality::Full);
        const Image moving = view.render(RenderQuality::Moving);
        EXPECT_EQ(view.lastQuality(), RenderQuality::Moving);
        ASSERT_EQ(moving.width(), full.width());
        ASSERT_EQ(moving.height(), full.height());
        // Reduced: not the full picture, yet close to it.
        EXPECT_GT(differingPixels(moving, full), 0) << "the moving frame is the full frame";
        EXPECT_LT(meanGreyDifference(moving, full), kMovingMeanGrey);
        // The bone at the sphere's projected centre (closed form), brighter than the fat beside it.
        const Vec2d c = expectedPixel("3d", mPhantom.centre, mBox.min, mBox.max, mFrame.pixelMm);
        const Vec2d fat = expectedPixel(
            "3d", mPhantom.centre + Vec3d(-2.0 * mPhantom.radius, 0, 0), mBox.min, mBox.max, mFrame.pixelMm);
        for (const Image* img : {&full, &moving}) {
            EXPECT_GT(greyAround(*img, c), greyAround(*img, fat) + kBoneOverFatGrey)
                << (img == &full ? "full" : "moving");
        }
        // Turned 90° (a horizontal drag): the sphere is where the camera frame
        // projects it, in the moving frame and then the full one.
        OrbitCamera cam(mFrame);
        cam.azimuth(-90.0);
        view.setCamera(cam.frame());
        const Vec2d turned = cam.frame().toPixel(mPhantom.centre);
        ASSERT_GT(std::abs(turned.x() - c.x()), 10.0) << "the test needs the turn to move the sphere";
        const Vec2d fatTurned = cam.frame().toPixel(mPhantom.centre + Vec3d(0, 2.0 * mPhantom.radius, 0));
        const Image movingTurned = view.render(RenderQuality::Moving);
        const Image fullTurned = view.render(RenderQuality::Full);
        for (const Image* img : {&fullTurned, &movingTurned}) {
            EXPECT_GT(greyAround(*img, turned), greyAround(*img, fatTurned) + kBoneOverFatGrey)
                << (img == &fullTurned ? "full, turned" : "moving, turned");
        }
        // Back at full quality the picture is the full path's again: the same as
        // a full frame before any moving one, at the home camera.
        view.setCamera(mFrame);
        EXPECT_EQ(differingPixels(view.render(RenderQuality::Full), full), 0) << "full quality restored";
    }
}

/// The triangles a marching-cells surface (discrete flying edges) draws of a
/// spherical shell of label samples on a cubic lattice of step h, from the
/// geometry alone: [low, high].
/// - Each lattice edge whose two samples differ in label holds one vertex, so
///   the vertices are the label changes along the lattice lines. A line through
///   the shell changes label twice at the outer sphere, and twice more where it
///   passes through the hole (the 2 mm wall is longer than h along any line, so
///   each side keeps a sample). Per axis, V_axis = 2·(N_R + N_r): N_ρ the lines
///   with a sample inside the sphere of radius ρ.
/// - A line at distance d from the centre has a sample inside when its chord
///   2·sqrt(ρ² − d²) ≥ h, and none when d ≥ ρ: N_ρ lies between the lattice
///   points of the discs of radius sqrt(ρ² − h²/4) and ρ, and the lattice points
///   of a disc of radius a (in steps h) number within π·(a ∓ √2/2)² (the unit
///   squares about them lie inside the disc of radius a + √2/2 and cover the
///   one of a − √2/2).
/// - The two sheets are closed surfaces of the sphere's topology (Euler
///   characteristic 2 each) whose triangles share each edge with one other:
///   V − 3T/2 + T = 4, so T = 2·V − 8.
/// The area and the step set the count, ≈ 3·A/h² (A the two spheres' area); the
/// bounds hold whatever the lattice's offset.
std::pair<double, double> shellTriangles(double outerMm, double innerMm, double hMm)
{
    const double half = std::sqrt(2.0) / 2.0;
    const auto lo = [&](double rho) {
        const double a = std::sqrt(rho * rho - 0.25) - half;
        return a > 0 ? std::numbers::pi * a * a : 0.0;
    };
    const auto hi = [&](double rho) { return std::numbers::pi * (rho + half) * (rho + half); };
    const double ro = outerMm / hMm, ri = innerMm / hMm;
    const double vLo = 3 * 2 * (lo(ro) + lo(ri)), vHi = 3 * 2 * (hi(ro) + hi(ri));
    return {2 * vLo - 8, 2 * vHi - 8};
}

TEST_F(Interactive3d, MovingFramesDrawTheCriticalSurfacesFromTheSampledLabelMap)
{
    // The graded sphere: an aorta shell (a critical tissue) from r·2/3 to r.
    mPhantom.graded = true;
    volume::GridSpec grid;
    grid.spacing = Vec3d(0.5, 0.5, 0.5);
    const volume::Volume labelled = mPhantom.make(grid);
    const RenderVolume rv(labelled, true);
    View3dStyle style; // Subsample x3, full step 1 voxel: the moving step is 3 voxels
    Overlays none;
    none.letters = false, none.scaleBar = false;
    VolumeView3d view(rv, mFrame, style, volume::TissueTable::builtin(), none);
    const Image full = view.render(RenderQuality::Full);
    const std::size_t fullTriangles = view.criticalTriangles();
    ASSERT_GT(fullTriangles, 0u) << "the aorta shell has a surface";
    const Image moving = view.render(RenderQuality::Moving);
    const std::size_t movingTriangles = view.criticalTriangles();
    ASSERT_GT(movingTriangles, 0u) << "the surfaces are drawn while moving too";
    // The aorta shell from 2r/3 to r, its labels sampled every voxel (0.5 mm) for
    // the full picture and every movingFactor·sampleVoxels voxels while moving.
    const double f = style.movingFactor * style.sampleVoxels; // voxels per sample, each axis (isotropic grid)
    const double outer = mPhantom.radius, inner = 2.0 * mPhantom.radius / 3.0;
    const auto [fullLo, fullHi] = shellTriangles(outer, inner, 0.5 * style.sampleVoxels);
    EXPECT_GE(double(fullTriangles), fullLo);
    EXPECT_LE(double(fullTriangles), fullHi);
    const auto [movingLo, movingHi] = shellTriangles(outer, inner, 0.5 * f);
    EXPECT_GE(double(movingTriangles), movingLo);
    EXPECT_LE(double(movingTriangles), movingHi);
    EXPECT_LT(movingHi, fullLo) << "the control: surfaces drawn at full resolution while moving fail the bound";
    // Still the sphere where it was: bright at its projected centre, close to the full picture.
    const Vec2d c = expectedPixel("3d", mPhantom.centre, mBox.min, mBox.max, mFrame.pixelMm);
    const Vec2d fat =
        expectedPixel("3d", mPhantom.centre + Vec3d(-2.0 * mPhantom.radius, 0, 0), mBox.min, mBox.max, mFrame.pixelMm);
    EXPECT_GT(greyAround(moving, c), greyAround(moving, fat) + kBoneOverFatGrey);
    EXPECT_LT(meanGreyDifference(moving, full), kMovingMeanGrey);
    // Released: the full-resolution surfaces again, the full picture pixel for pixel.
    EXPECT_EQ(differingPixels(view.render(RenderQuality::Full), full), 0);
    EXPECT_EQ(view.criticalTriangles(), fullTriangles);
}

/// The viewer's 3D pane driven by synthetic drag, wheel, release and key events.
class Viewer3dCamera : public Interactive3d {
protected:
    void SetUp() override
    {
        Interactive3d::SetUp();
        if (IsSkipped()) return;
        mOpt.width = 244, mOpt.height = 268; // 120 px panes
        mOpt.point = mPhantom.centre;
        mOpt.threeD = true;
    }
    static ViewerEvent drag(double dx, double dy)
    {
        ViewerEvent e;
        e.kind = ViewerEvent::Kind::Drag;
        e.pane = ViewKind::ThreeD;
        e.px = Vec2d(dx, dy);
        return e;
    }
    ViewerOptions mOpt;
};

TEST_F(Viewer3dCamera, DragRotatesWhileMovingAndReleaseRendersFullQuality)
{
    Viewer v(*mVolume, mOpt, test::table());
    const ViewFrame home = v.frame(ViewKind::ThreeD);
    v.render();
    EXPECT_EQ(v.last3dQuality(), RenderQuality::Full);
    // A drag of 45/200 of the pane's width: azimuth −45° about the view up.
    v.handle(drag(home.width * 45.0 / kOrbitDegreesPerPane, 0));
    const double c = std::cos(std::numbers::pi / 4), s = std::sin(std::numbers::pi / 4);
    EXPECT_TRUE(nearVec(v.frame(ViewKind::ThreeD).normal, Vec3d(s, c, 0), kCameraTol));
    EXPECT_TRUE(nearVec(v.frame(ViewKind::ThreeD).down, home.down, kCameraTol));
    EXPECT_TRUE(v.moving());
    v.render();
    EXPECT_EQ(v.last3dQuality(), RenderQuality::Moving) << "while the button is held";
    // Held still: a drag does not settle by time, only by its release.
    EXPECT_FALSE(v.settle(std::chrono::steady_clock::now() + std::chrono::seconds(10)));
    v.handle(ViewerEvent{ViewerEvent::Kind::Release, ViewKind::ThreeD, {0, 0}, "", 0});
    EXPECT_FALSE(v.moving());
    v.render();
    EXPECT_EQ(v.last3dQuality(), RenderQuality::Full) << "after the release";
    // The slices are untouched by the 3D camera.
    EXPECT_EQ(v.point(), mPhantom.centre);
    // r resets the camera to the first one, exactly.
    v.handle(ViewerEvent{ViewerEvent::Kind::Key, ViewKind::Axial, {0, 0}, "r", 0});
    EXPECT_TRUE(v.camera().atHome());
    EXPECT_EQ(v.frame(ViewKind::ThreeD).normal, home.normal);
    EXPECT_EQ(v.frame(ViewKind::ThreeD).origin, home.origin);
}

TEST_F(Viewer3dCamera, WheelZoomsAndFullQualityFollowsTheSettleTime)
{
    Viewer v(*mVolume, mOpt, test::table());
    const ViewFrame home = v.frame(ViewKind::ThreeD);
    // The wheel over the 3D pane, in window pixels: one step in.
    const PaneRect& pane = v.layout().pane(ViewKind::ThreeD);
    const auto before = std::chrono::steady_clock::now();
    v.scrollWindow(pane.x + pane.width / 2, pane.y + pane.height / 2, 1);
    EXPECT_NEAR(v.frame(ViewKind::ThreeD).pixelMm, home.pixelMm / kWheelZoom, kCameraTol * home.pixelMm);
    EXPECT_TRUE(nearVec(v.frame(ViewKind::ThreeD).centre(), home.centre(), kCameraTol));
    v.render();
    EXPECT_EQ(v.last3dQuality(), RenderQuality::Moving);
    EXPECT_FALSE(v.settle(before)) << "before the settle time";
    EXPECT_FALSE(v.dirty());
    const auto later = std::chrono::steady_clock::now() + std::chrono::milliseconds(int(1000 * kSettleS) + 1);
    EXPECT_TRUE(v.settle(later));
    EXPECT_TRUE(v.dirty()) << "the full-quality redraw is due";
    v.render();
    EXPECT_EQ(v.last3dQuality(), RenderQuality::Full);
    // A window drag: button down in the 3D pane, motion, release. Whole
    // pixels: dy px turn the camera by dy · 200 / height degrees (Elevation).
    const int dy = int(home.height * 90.0 / kOrbitDegreesPerPane);
    const double theta = dy * kOrbitDegreesPerPane / home.height * std::numbers::pi / 180.0;
    EXPECT_TRUE(v.clickWindow(pane.x + 10, pane.y + 10));
    v.dragWindow(pane.x + 10, pane.y + 10 + dy);
    EXPECT_TRUE(v.moving());
    v.releaseWindow();
    EXPECT_FALSE(v.moving());
    EXPECT_TRUE(nearVec(v.frame(ViewKind::ThreeD).normal, Vec3d(0, std::cos(theta), -std::sin(theta)), kCameraTol));
    // A drag that starts on a slice does not turn the 3D camera.
    const ViewFrame turned = v.frame(ViewKind::ThreeD);
    const Vec2d axial = v.imageOrigin(ViewKind::Axial);
    v.clickWindow(int(axial.x()) + 5, int(axial.y()) + 5);
    v.dragWindow(int(axial.x()) + 50, int(axial.y()) + 5);
    v.releaseWindow();
    EXPECT_EQ(v.frame(ViewKind::ThreeD).normal, turned.normal);
}

} // namespace
} // namespace voxhap::render
