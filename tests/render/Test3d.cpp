// SPDX-License-Identifier: Apache-2.0
/// @file Test3d.cpp
/// @brief The 3D view under Xvfb (started by DisplayGuard when there is no
/// display): size, not blank, and a graded bright sphere whose maximum and
/// summed projections peak at the sphere's projected centre (closed form).

#include "RenderFixtures.h"

#include "common/Prerequisites.h"

#include "core/Errors.h"
#include "render/views/RenderVolume.h"
#include "render/volume3d/Display.h"
#include "render/volume3d/VolumeView3d.h"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <unistd.h>

namespace voxhap::render {
namespace {

using test::expectedPixel;
using test::SpherePhantom;

/// The projection peak against the projected centre: the issue's ± 2 px. The
/// bright core (radius 2 mm = 4 px) is symmetric, so its centroid is off only
/// by the voxelisation (half a 0.5 mm voxel = 0.5 px) and VTK's half-pixel
/// conventions; 2 px leaves room for both and still catches a mirrored or
/// shifted view (the centre is 10 px and more from the image centre).
constexpr double kPeakPx = 2.0;

class View3d : public testing::Test {
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
        mPhantom.graded = true;
        mPhantom.radius = 6.0;
        mPhantom.box = {Vec3d(-12, -30, -14), Vec3d(22, 0, 18)};
        volume::GridSpec grid;
        grid.spacing = Vec3d(0.5, 0.5, 0.5);
        mVolume = std::make_unique<volume::Volume>(mPhantom.make(grid));
        const auto b = mVolume->worldBounds();
        mBox = {b[0], b[1]};
        mFrame = viewFrame(ViewKind::ThreeD, mBox, 0.5 * (mBox.min + mBox.max), 0.5);
    }
    Image render(BlendMode mode, bool labels = false, RayCaster caster = RayCaster::Auto)
    {
        const RenderVolume rv(*mVolume, labels);
        View3dStyle style;
        style.mode = mode;
        style.caster = caster;
        style.window = {2000.0, 900.0}; // the core (1850 HU) near white, the shells darker
        style.criticalSurfaces = labels;
        VolumeView3d view(
            rv, mFrame, style, volume::TissueTable::builtin(), Overlays{{}, {}, {}, "", false, false, ""});
        return view.render();
    }
    static DisplayGuard* sDisplay;
    SpherePhantom mPhantom;
    std::unique_ptr<volume::Volume> mVolume;
    WorldBounds mBox;
    ViewFrame mFrame;
};

DisplayGuard* View3d::sDisplay = nullptr;

/// Centroid of the pixels within 2 grey levels of the brightest one.
Vec2d peak(const Image& img)
{
    int top = 0;
    for (int y = 0; y < img.height(); ++y) {
        for (int x = 0; x < img.width(); ++x) top = std::max(top, int(img.at(x, y).g));
    }
    return test::centroid(img, [top](const Rgb& p) { return int(p.g) >= top - 2; });
}

TEST_F(View3d, MipPeaksAtTheProjectedCentre)
{
    const Vec2d expected = expectedPixel("3d", mPhantom.centre, mBox.min, mBox.max, mFrame.pixelMm);
    for (const RayCaster caster : {RayCaster::Cpu, RayCaster::Gpu}) {
        const Image img = render(BlendMode::Mip, false, caster);
        ASSERT_EQ(img.width(), mFrame.width);
        ASSERT_EQ(img.height(), mFrame.height);
        EXPECT_GT(test::greySpread(img), 5.0) << "blank image";
        const Vec2d got = peak(img);
        EXPECT_NEAR(got.x(), expected.x(), kPeakPx) << (caster == RayCaster::Cpu ? "cpu" : "gpu");
        EXPECT_NEAR(got.y(), expected.y(), kPeakPx) << (caster == RayCaster::Cpu ? "cpu" : "gpu");
    }
}

TEST_F(View3d, EveryFreshViewOfAWideFrameDrawsTheVolumeWhereTheCameraProjectsIt)
{
    // A frame three times wider than high, from the front, centred 30 mm to
    // the patient's right of the sphere and level with it: the sphere's
    // centre projects 60 px right of the image centre (x = L), on its middle row.
    constexpr int kW = 240, kH = 80;
    constexpr double kOffsetMm = 30.0;
    ViewFrame f = mFrame;
    f.width = kW, f.height = kH;
    const Vec3d centre(mPhantom.centre.x() - kOffsetMm, 0.5 * (mBox.min.y() + mBox.max.y()), mPhantom.centre.z());
    f.origin = centre - f.pixelMm * (0.5 * (kW - 1) * f.right + 0.5 * (kH - 1) * f.down);
    ASSERT_EQ(f.right, Vec3d(1, 0, 0)) << "the test's closed form assumes the front view";
    const Vec2d expected(0.5 * (kW - 1) + kOffsetMm / f.pixelMm, 0.5 * (kH - 1));
    // Views built and destroyed one after another, as the viewer, plan and
    // the bench do: VTK 9.1 could give a new renderer a stale 1 : 1 aspect,
    // and its CPU ray caster then cast the rays three times too far apart
    // sideways (the sphere 180 px off centre, outside the image) in about one
    // fresh view out of six. Twelve views make a miss very likely to show.
    const RenderVolume rv(*mVolume, false);
    View3dStyle style;
    style.mode = BlendMode::Mip;
    style.caster = RayCaster::Cpu;
    style.window = {2000.0, 900.0};
    for (int i = 0; i < 12; ++i) {
        SCOPED_TRACE("view " + std::to_string(i));
        VolumeView3d view(rv, f, style, volume::TissueTable::builtin(), Overlays{{}, {}, {}, "", false, false, ""});
        const Vec2d got = peak(view.render());
        EXPECT_NEAR(got.x(), expected.x(), kPeakPx);
        EXPECT_NEAR(got.y(), expected.y(), kPeakPx);
    }
}

TEST_F(View3d, SummedProjectionPeaksAtTheProjectedCentre)
{
    // The longest chord through the sphere (and its densest core) is the one
    // through the centre.
    const Image img = render(BlendMode::Sum);
    EXPECT_GT(test::greySpread(img), 5.0) << "blank image";
    const Vec2d expected = expectedPixel("3d", mPhantom.centre, mBox.min, mBox.max, mFrame.pixelMm);
    const Vec2d got = peak(img);
    EXPECT_NEAR(got.x(), expected.x(), kPeakPx);
    EXPECT_NEAR(got.y(), expected.y(), kPeakPx);
}

TEST_F(View3d, CompositeModesAreNotBlank)
{
    for (const BlendMode m : {BlendMode::Colour, BlendMode::Grey}) {
        const Image img = render(m, true, RayCaster::Gpu);
        EXPECT_EQ(img.width(), mFrame.width);
        EXPECT_GT(test::greySpread(img), 5.0) << blendModeName(m);
    }
}

/// Whether a path-coloured pixel lies within 2 px of @p at (the line is 2 px wide).
bool pathColourNear(const Image& img, const Vec2d& at)
{
    const Rgb want = OverlayStyle{}.path;
    for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) {
            const int x = int(std::lround(at.x())) + dx, y = int(std::lround(at.y())) + dy;
            if (x < 0 || y < 0 || x >= img.width() || y >= img.height()) continue;
            const Rgb p = img.at(x, y);
            if (std::abs(p.r - want.r) <= 8 && std::abs(p.g - want.g) <= 8 && std::abs(p.b - want.b) <= 8) return true;
        }
    }
    return false;
}

TEST_F(View3d, PathBehindTheBodyIsShownOnlyWhenLinesAreOnTop)
{
    // A path 3 mm behind the sphere (seen from the camera), crossing its
    // projected centre: the opaque core hides it in a composite rendering,
    // and the overview's layer above (plan's fourth quadrant) shows it.
    const Vec3d behind = mPhantom.centre + (mPhantom.radius + 3.0) * mFrame.normal;
    Overlays o{{}, {}, {}, "", false, false, ""};
    o.paths.push_back({"p", behind + 4.0 * mFrame.down, behind - 4.0 * mFrame.down, std::nullopt});
    const Vec2d centre = expectedPixel("3d", mPhantom.centre, mBox.min, mBox.max, mFrame.pixelMm);
    const RenderVolume rv(*mVolume, false);
    for (const bool onTop : {false, true}) {
        View3dStyle style;
        style.mode = BlendMode::Grey;
        style.window = {400.0, 200.0}; // opacity rises to bone's 0.3/mm from 400 HU: the cortical core is dense
        style.criticalSurfaces = false;
        style.linesOnTop = onTop;
        VolumeView3d view(rv, mFrame, style, volume::TissueTable::builtin(), o);
        EXPECT_EQ(pathColourNear(view.render(), centre), onTop) << (onTop ? "on top" : "in the scene");
    }
}

TEST(Display, NoReachableDisplayIsReplacedThenRestored)
{
    // An unreachable $DISPLAY must not reach VTK: the guard starts Xvfb instead
    // and puts the old value back afterwards.
    ::setenv("DISPLAY", ":65000", 1); // nothing listens there
    {
        DisplayGuard guard;
        ASSERT_TRUE(guard.available()) << guard.why();
        EXPECT_EQ(guard.kind(), DisplayKind::Xvfb);
        EXPECT_STREQ(std::getenv("DISPLAY"), guard.display().c_str());
        EXPECT_TRUE(displayReachable(guard.display()));
    }
    EXPECT_STREQ(std::getenv("DISPLAY"), ":65000");
    EXPECT_FALSE(displayReachable(":65000"));
}

/// Xvfb processes (running or zombie) whose parent is this process, from /proc.
int xvfbChildren()
{
    int n = 0;
    for (const auto& e : std::filesystem::directory_iterator("/proc")) {
        std::ifstream stat(e.path() / "stat");
        std::string pid, comm, state;
        long ppid = 0;
        if (stat >> pid >> comm >> state >> ppid && comm == "(Xvfb)" && ppid == long(::getpid())) ++n;
    }
    return n;
}

TEST(Display, AStartBegunWithoutWaitingIsFinishedByWaitOrStoppedUnwaited)
{
    // `voxhap plan` starts Xvfb before it loads and waits for it at the views.
    ::setenv("DISPLAY", ":65000", 1); // nothing listens there
    {
        DisplayGuard guard(10.0, false);
        EXPECT_FALSE(guard.available()) << "not usable before wait()";
        EXPECT_STREQ(std::getenv("DISPLAY"), ":65000") << "$DISPLAY untouched until wait()";
        guard.wait();
        ASSERT_TRUE(guard.available()) << guard.why();
        EXPECT_EQ(guard.kind(), DisplayKind::Xvfb);
        EXPECT_TRUE(displayReachable(guard.display()));
        guard.wait(); // a second wait changes nothing
        EXPECT_TRUE(displayReachable(guard.display()));
    }
    EXPECT_STREQ(std::getenv("DISPLAY"), ":65000");
    // Dropped before anyone waited (a plan that failed while loading): the
    // server it started is stopped and reaped, and $DISPLAY was never changed.
    const int before = xvfbChildren();
    {
        DisplayGuard guard(10.0, false);
        // Forked at once; its name reads Xvfb once the child has exec'd, which a
        // loaded machine may delay: poll for it (a guard that never started one
        // fails after the deadline).
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
        while (xvfbChildren() != before + 1 && std::chrono::steady_clock::now() < deadline)
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
        EXPECT_EQ(xvfbChildren(), before + 1) << "the server is started at once";
    }
    EXPECT_EQ(xvfbChildren(), before) << "stopped and reaped (a zombie still counts)";
    EXPECT_STREQ(std::getenv("DISPLAY"), ":65000");
}

TEST(Display, ThreeDViewRefusesWithoutDisplay)
{
    ::unsetenv("DISPLAY");
    SpherePhantom p;
    volume::GridSpec grid;
    grid.spacing = Vec3d(2, 2, 2);
    const volume::Volume v = p.make(grid);
    const RenderVolume rv(v, false);
    const auto b = v.worldBounds();
    const ViewFrame f = viewFrame(ViewKind::ThreeD, {b[0], b[1]}, p.centre, 2.0);
    EXPECT_THROW(VolumeView3d(rv, f, View3dStyle{}, volume::TissueTable::builtin(), Overlays{}), ValueError);
}

} // namespace
} // namespace voxhap::render
