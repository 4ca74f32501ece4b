// SPDX-License-Identifier: Apache-2.0
/// @file TestViewer.cpp
/// @brief The interactive viewer without a user: measurements against closed
/// forms, the click state machine, the pane layout, the event script parser,
/// and the whole viewer driven by synthetic clicks on an asymmetric phantom —
/// the plan holds the clicked world points, the window image has the size
/// asked for, and path and needle are drawn where the projection puts them.

#include "RenderFixtures.h"

#include "common/BuiltinTable.h"
#include "common/TempDirTest.h"
#include "common/Tolerances.h"
#include "core/Errors.h"
#include "render/viewer/Measurement.h"
#include "render/viewer/PlanEditor.h"
#include "render/viewer/Viewer.h"
#include "render/viewer/ViewerLayout.h"
#include "render/viewer/ViewerScript.h"
#include "render/volume3d/Display.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <numbers>

namespace voxhap::render {
namespace {

using test::expectedPixel;
using test::halfVoxel;
using test::nearVec;
using test::SpherePhantom;

/// Distances and angles of exact small-integer inputs: a few roundings of
/// doubles of order 100, so 1e-12 is far above round-off and far below any
/// displayed digit.
constexpr double kMeasureTol = 1e-12;

TEST(Measurement, DistanceIsEuclidean)
{
    // 3-4-12 is a Pythagorean quadruple: the distance is exactly 13.
    EXPECT_NEAR(distanceMm(Vec3d(1, 2, 3), Vec3d(4, 6, 15)), 13.0, kMeasureTol);
    EXPECT_EQ(distanceMm(Vec3d(1, 2, 3), Vec3d(1, 2, 3)), 0.0);
}

TEST(Measurement, AngleBetweenSegments)
{
    const Segment x{Vec3d(0, 0, 0), Vec3d(5, 0, 0)};
    EXPECT_NEAR(*angleDeg(x, {Vec3d(1, 1, 1), Vec3d(3, 3, 1)}), 45.0, kMeasureTol);
    EXPECT_NEAR(*angleDeg(x, {Vec3d(0, 0, 0), Vec3d(0, 0, -2)}), 90.0, kMeasureTol);
    EXPECT_NEAR(*angleDeg(x, {Vec3d(2, 0, 0), Vec3d(-7, 0, 0)}), 180.0, kMeasureTol);
    // The angle of the unit cube's diagonal with an edge: acos(1/sqrt(3)).
    EXPECT_NEAR(*angleDeg(x, {Vec3d(0, 0, 0), Vec3d(1, 1, 1)}),
        std::acos(1.0 / std::sqrt(3.0)) * 180.0 / std::numbers::pi, kMeasureTol);
    // Nearly parallel: 1e-7 rad. acos(cos θ) would lose it (cos θ = 1 − 5e-15);
    // atan2 keeps it to round-off relative to θ.
    const double theta = 1e-7;
    const auto tiny = angleDeg(x, {Vec3d(0, 0, 0), Vec3d(std::cos(theta), std::sin(theta), 0)});
    EXPECT_NEAR(*tiny, theta * 180.0 / std::numbers::pi, 1e-9 * theta * 180.0 / std::numbers::pi);
    // A zero-length segment has no direction.
    EXPECT_FALSE(angleDeg(x, {Vec3d(1, 1, 1), Vec3d(1, 1, 1)}).has_value());
}

TEST(PlanEditor, EntryThenTargetMakesOnePathThatLaterPairsReplace)
{
    planning::Plan loaded;
    loaded.paths.push_back({"L3", Vec3d(0, 0, 0), Vec3d(0, 10, 0), std::nullopt});
    PlanEditor e(loaded);
    EXPECT_EQ(e.click(Vec3d(1, 2, 3)), std::optional<Vec3d>(Vec3d(1, 2, 3))) << "navigate moves the crosshair";
    e.setTool(Tool::Plan);
    EXPECT_FALSE(e.click(Vec3d(1, 2, 3)).has_value());
    ASSERT_TRUE(e.pendingEntry().has_value());
    EXPECT_EQ(e.plan().paths.size(), 1u) << "no path before the target";
    e.click(Vec3d(1, 2, 3)); // the entry again: no direction, ignored
    EXPECT_EQ(e.plan().paths.size(), 1u);
    e.click(Vec3d(4, 5, 6));
    ASSERT_EQ(e.plan().paths.size(), 2u);
    EXPECT_EQ(e.plan().paths[0].name, "L3") << "loaded paths are kept";
    EXPECT_EQ(e.plan().paths[1].entry, Vec3d(1, 2, 3));
    EXPECT_EQ(e.plan().paths[1].target, Vec3d(4, 5, 6));
    EXPECT_FALSE(e.pendingEntry().has_value());
    // A third click starts a new entry; the complete path stays until the new target.
    e.click(Vec3d(7, 7, 7));
    EXPECT_EQ(e.plan().paths[1].target, Vec3d(4, 5, 6));
    e.click(Vec3d(9, 9, 9));
    ASSERT_EQ(e.plan().paths.size(), 2u) << "the viewer's path is replaced, not added";
    EXPECT_EQ(e.plan().paths[1].entry, Vec3d(7, 7, 7));
    EXPECT_EQ(e.plan().paths[1].target, Vec3d(9, 9, 9));
}

TEST(PlanEditor, DistanceAndAngleTools)
{
    PlanEditor e;
    e.setTool(Tool::Distance);
    e.click(Vec3d(0, 0, 0));
    EXPECT_FALSE(e.distance().has_value());
    EXPECT_EQ(e.pendingPoints().size(), 1u);
    e.click(Vec3d(0, 3, 4));
    ASSERT_TRUE(e.distance().has_value());
    EXPECT_NEAR(e.distance()->lengthMm(), 5.0, kMeasureTol);
    EXPECT_NE(e.status().find("distance 5.0 mm"), std::string::npos) << e.status();
    e.setTool(Tool::Angle);
    for (const Vec3d& p : {Vec3d(0, 0, 0), Vec3d(1, 0, 0), Vec3d(0, 0, 0)}) e.click(p);
    e.setTool(Tool::Distance); // switching tools drops the half-picked angle
    EXPECT_TRUE(e.pendingPoints().empty());
    e.setTool(Tool::Angle);
    for (const Vec3d& p : {Vec3d(0, 0, 0), Vec3d(1, 0, 0), Vec3d(0, 0, 0), Vec3d(0, 2, 2)}) e.click(p);
    ASSERT_TRUE(e.angle().has_value());
    EXPECT_NEAR(*angleDeg(e.angle()->first, e.angle()->second), 90.0, kMeasureTol);
    EXPECT_NE(e.status().find("angle 90.0 deg"), std::string::npos) << e.status();
    e.clearMeasurements();
    EXPECT_FALSE(e.distance().has_value());
    EXPECT_FALSE(e.angle().has_value());
}

TEST(ViewerLayout, PanesTileTheWindowAndHitsInvertPlacement)
{
    const int w = 301, h = 427, status = 24, gap = 4;
    const ViewerLayout l = viewerLayout(w, h, status, gap);
    // Every window pixel lies in at most one pane; the panes cover all but the
    // gaps and the status bar (counted in closed form).
    long covered = 0;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            int n = 0;
            for (const PaneRect& p : l.panes) n += p.contains(x, y);
            ASSERT_LE(n, 1) << x << "," << y;
            covered += n;
        }
    }
    EXPECT_EQ(covered, long(w - gap) * long(h - status - gap));
    EXPECT_EQ(l.pane(ViewKind::Axial).x, 0);
    EXPECT_EQ(l.pane(ViewKind::Axial).y, 0);
    EXPECT_GT(l.pane(ViewKind::Sagittal).x, l.pane(ViewKind::Axial).x);
    EXPECT_GT(l.pane(ViewKind::Coronal).y, l.pane(ViewKind::Axial).y);
    EXPECT_EQ(l.pane(ViewKind::ThreeD).x + l.pane(ViewKind::ThreeD).width, w);
    EXPECT_EQ(l.pane(ViewKind::ThreeD).y + l.pane(ViewKind::ThreeD).height, h - status);
    // A 50 × 40 image in each pane: its pixel (7, 9) is hit at its origin + (7, 9).
    const std::array<std::array<int, 2>, 4> sizes{{{50, 40}, {50, 40}, {50, 40}, {50, 40}}};
    for (const PaneRect& p : l.panes) {
        const Vec2d o = imageOrigin(p, 50, 40);
        EXPECT_EQ(o.x(), p.x + (p.width - 50) / 2);
        const auto hit = hitPane(l, int(o.x()) + 7, int(o.y()) + 9, sizes);
        ASSERT_TRUE(hit.has_value());
        EXPECT_EQ(hit->view, p.view);
        EXPECT_EQ(hit->px, Vec2d(7, 9));
    }
    EXPECT_FALSE(hitPane(l, w / 2 - 1, 5, sizes).has_value()) << "the gap";
    EXPECT_FALSE(hitPane(l, 5, h - 2, sizes).has_value()) << "the status bar";
    EXPECT_THROW(viewerLayout(30, 30, status), ValueError);
}

TEST(ViewerScript, ParsesStepsAndNamesTheBadLine)
{
    const auto steps = parseViewerScript("# plan\nkey p\nclick axial 12.5 30  # entry\n\nscroll coronal -3\n"
                                         "wait-pose 2\nsleep 0.1\n",
        "ev.txt");
    ASSERT_EQ(steps.size(), 5u);
    EXPECT_EQ(steps[0].event.key, "p");
    EXPECT_EQ(steps[1].event.kind, ViewerEvent::Kind::Click);
    EXPECT_EQ(steps[1].event.pane, ViewKind::Axial);
    EXPECT_EQ(steps[1].event.px, Vec2d(12.5, 30));
    EXPECT_EQ(steps[1].line, 3);
    EXPECT_EQ(steps[2].event.steps, -3);
    EXPECT_EQ(steps[3].kind, ScriptStep::Kind::WaitPose);
    EXPECT_EQ(steps[3].seconds, 2.0);
    const auto message = [](const std::string& text) {
        try {
            parseViewerScript(text, "ev.txt");
        } catch (const ValueError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_NE(message("key p\nclick axial 1\n").find("ev.txt:2: missing y"), std::string::npos);
    EXPECT_NE(message("click front 1 2\n").find("ev.txt:1: unknown pane 'front'"), std::string::npos);
    EXPECT_NE(message("jump\n").find("ev.txt:1: unknown step 'jump'"), std::string::npos);
    EXPECT_NE(message("click axial 1 nan\n").find("ev.txt:1: y 'nan'"), std::string::npos);
    EXPECT_NE(message("scroll axial 1.5\n").find("integer"), std::string::npos);
    EXPECT_NE(message("key p q\n").find("unexpected 'q'"), std::string::npos);
}

TEST(Plan, WrittenPlanReadsBack)
{
    planning::Plan p;
    p.paths.push_back({"a", Vec3d(1.25, -2, 3), Vec3d(4, 5, -6.5), std::nullopt});
    p.paths.push_back(
        {"b", Vec3d(0, 0, 0), Vec3d(0, 0, 1), planning::NeedlePose{Vec3d(0, 0, 1), Vec3d(0, 0, 1), 80.0}});
    const planning::Plan q = planning::parsePlan(planning::planJson(p), "memory");
    ASSERT_EQ(q.paths.size(), 2u);
    EXPECT_EQ(q.paths[0].entry, p.paths[0].entry); // JSON keeps doubles exactly (round-trip printing)
    EXPECT_EQ(q.paths[0].target, p.paths[0].target);
    EXPECT_EQ(q.paths[1].name, "b");
    ASSERT_TRUE(q.paths[1].needle.has_value());
    EXPECT_EQ(q.paths[1].needle->lengthMm, 80.0);
    EXPECT_TRUE(q.paths[1].needle->shaft.empty());
    // A bending needle's shaft (physics.md §9) reads back point for point.
    p.paths[1].needle->shaft = {Vec3d(0, 0, -79), Vec3d(0.5, 0, -40), Vec3d(1.25, 0, 1)};
    const planning::Plan bent = planning::parsePlan(planning::planJson(p), "memory");
    EXPECT_EQ(bent.paths[1].needle->shaft, p.paths[1].needle->shaft);
    // Control: a shaft of one point is refused, naming the field.
    const std::string one = R"({"schema": "voxhap-plan/1", "paths": [{"entry": [0, 0, 0], "target": [0, 0, 1],
        "needle": {"tip": [0, 0, 1], "direction": [0, 0, 1], "shaft": [[0, 0, 0]]}}]})";
    try {
        (void)planning::parsePlan(one, "plan.json");
        ADD_FAILURE() << "a one-point shaft was accepted";
    } catch (const ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("needle.shaft"), std::string::npos) << e.what();
    }
}

/// The viewer on the asymmetric sphere phantom (1 mm voxels), driven by
/// synthetic events. Without the 3D pane unless a test turns it on.
class ViewerTest : public test::TempDirTest {
protected:
    void SetUp() override
    {
        TempDirTest::SetUp();
        volume::GridSpec grid;
        grid.spacing = Vec3d(1, 1, 1);
        mVolume = std::make_unique<volume::Volume>(mPhantom.make(grid));
        const auto b = mVolume->worldBounds();
        mLo = b[0], mHi = b[1];
        mOpt.width = 244,
        mOpt.height = 268; // panes of 120 × 120 px: the box's 60 mm side fills one at 0.5 mm per pixel
        mOpt.threeD = false;
        mOpt.point = mPhantom.centre;
        mOpt.planOut = mDir / "plan.json";
    }
    ViewerEvent click(ViewKind pane, const Vec2d& px)
    {
        ViewerEvent e;
        e.kind = ViewerEvent::Kind::Click;
        e.pane = pane;
        e.px = px;
        return e;
    }
    ViewerEvent key(const std::string& k)
    {
        ViewerEvent e;
        e.key = k;
        return e;
    }
    /// Window pixel of world point @p p in pane @p v (closed form plus the pane's placement).
    Vec2d windowPixel(const Viewer& v, ViewKind k, const Vec3d& p)
    {
        return v.imageOrigin(k) + expectedPixel(std::string(viewName(k)), p, mLo, mHi, v.frame(k).pixelMm);
    }
    SpherePhantom mPhantom;
    std::unique_ptr<volume::Volume> mVolume;
    Vec3d mLo, mHi;
    ViewerOptions mOpt;
};

/// A pixel within @p radius of (x, y) with colour @p c exactly: lines are
/// rasterised to the nearest pixel and may be a pixel wide, so the drawn pixel
/// closest to a point on the line is within 1 px of it.
bool colourNear(const Image& img, const Vec2d& at, Rgb c, int radius = 1)
{
    for (int dy = -radius; dy <= radius; ++dy) {
        for (int dx = -radius; dx <= radius; ++dx) {
            const int x = int(std::lround(at.x())) + dx, y = int(std::lround(at.y())) + dy;
            if (img.contains(x, y) && img.at(x, y) == c) return true;
        }
    }
    return false;
}

TEST_F(ViewerTest, TwoClicksOnTheAxialSlicePlanAPathAtThoseWorldPoints)
{
    Viewer v(*mVolume, mOpt, test::table());
    // One pixel size in every pane: the largest extent (z, 60 mm) over the pane (120 px).
    for (ViewKind k : {ViewKind::Axial, ViewKind::Sagittal, ViewKind::Coronal, ViewKind::ThreeD}) {
        EXPECT_EQ(v.frame(k).pixelMm, 0.5) << viewName(k);
    }
    const Vec3d entry(-20, -35, mPhantom.centre.z()), target = mPhantom.centre; // both on the axial slice z = 5
    // Click whole pixels, as a mouse does: the world point is then off by up to
    // half a pixel (0.25 mm), within half a voxel.
    const auto px = [&](const Vec3d& p) {
        const Vec2d e = expectedPixel("axial", p, mLo, mHi, 0.5);
        return Vec2d(std::round(e.x()), std::round(e.y()));
    };
    EXPECT_TRUE(v.handle(key("p")));
    EXPECT_TRUE(v.handle(click(ViewKind::Axial, px(entry))));
    EXPECT_TRUE(v.handle(click(ViewKind::Axial, px(target))));
    EXPECT_TRUE(v.handle(key("s")));
    EXPECT_NE(v.lastMessage().find("saved"), std::string::npos) << v.lastMessage();
    const planning::Plan saved = planning::loadPlan(mDir / "plan.json");
    ASSERT_EQ(saved.paths.size(), 1u);
    EXPECT_TRUE(nearVec(saved.paths[0].entry, entry, halfVoxel(1.0)));
    EXPECT_TRUE(nearVec(saved.paths[0].target, target, halfVoxel(1.0)));

    const Image img = v.render();
    EXPECT_EQ(img.width(), mOpt.width);
    EXPECT_EQ(img.height(), mOpt.height);
    EXPECT_GT(test::greySpread(img), 5.0) << "blank window";
    // The path lies in the axial plane: drawn solid in the path colour along its projection.
    const OverlayStyle style;
    for (double t : {0.25, 0.5, 0.75}) {
        const Vec3d p = entry + t * (target - entry);
        EXPECT_TRUE(colourNear(img, windowPixel(v, ViewKind::Axial, p), style.path)) << "t = " << t;
    }
    // q quits.
    EXPECT_FALSE(v.handle(key("q")));
}

TEST_F(ViewerTest, NavigateMovesTheOtherSlicesAndScrollStepsOneVoxel)
{
    Viewer v(*mVolume, mOpt, test::table());
    const Vec3d p(-10, -20, 5);
    v.handle(click(ViewKind::Axial, expectedPixel("axial", p, mLo, mHi, 0.5)));
    EXPECT_TRUE(nearVec(v.point(), p, 1e-9)) << "navigate: the crosshair moves to the click";
    EXPECT_NEAR(v.frame(ViewKind::Sagittal).depth(p), 0.0, 1e-9) << "the sagittal slice passes through it";
    EXPECT_NEAR(v.frame(ViewKind::Coronal).depth(p), 0.0, 1e-9);
    ViewerEvent s;
    s.kind = ViewerEvent::Kind::Scroll;
    s.pane = ViewKind::Axial;
    s.steps = 3;
    v.handle(s);
    EXPECT_NEAR(v.point().z(), p.z() + 3.0, 1e-9) << "three 1 mm slices towards superior (+z)";
    v.handle(key("Down"));
    EXPECT_NEAR(v.point().z(), p.z() + 2.0, 1e-9) << "Down: one slice back in the pane last used";
}

TEST_F(ViewerTest, WindowClicksReachThePaneUnderThePointer)
{
    Viewer v(*mVolume, mOpt, test::table());
    // A mouse click in window pixels on the sagittal pane: the crosshair moves
    // to the world point under it (within half a pixel: the click is whole pixels).
    const Vec3d p(mPhantom.centre.x(), -30, 20);
    const Vec2d w = windowPixel(v, ViewKind::Sagittal, p);
    EXPECT_TRUE(v.clickWindow(int(std::lround(w.x())), int(std::lround(w.y()))));
    EXPECT_TRUE(nearVec(v.point(), p, 0.5 * v.frame(ViewKind::Sagittal).pixelMm));
    // The gap between panes and the 3D pane move nothing.
    const Vec3d before = v.point();
    EXPECT_TRUE(v.clickWindow(v.layout().pane(ViewKind::Axial).width + 1, 10));
    const Vec2d c3 = v.imageOrigin(ViewKind::ThreeD);
    EXPECT_TRUE(v.clickWindow(int(c3.x()) + 5, int(c3.y()) + 5));
    EXPECT_EQ(v.point(), before);
    EXPECT_NE(v.lastMessage().find("3d pane"), std::string::npos);
}

TEST_F(ViewerTest, ScriptPlayerWaitsOnTheCallersClockAndPoses)
{
    // Time is given, never slept: the player's waits end exactly where the steps say.
    Viewer v(*mVolume, mOpt, test::table());
    using Clock = ScriptPlayer::Clock;
    using std::chrono::milliseconds;
    const Clock::time_point t0{};
    ScriptPlayer play(
        parseViewerScript("key Up\nsleep 0.5\nkey Up\nwait-pose 2\nkey Up\nkey q\nkey Up\n", "ev.txt"), "ev.txt");
    const double z0 = v.point().z();
    EXPECT_TRUE(play.advance(v, 0, t0)); // the first key, then the sleep begins
    EXPECT_NEAR(v.point().z(), z0 + 1.0, 1e-9);
    EXPECT_TRUE(play.advance(v, 0, t0 + milliseconds(499)));
    EXPECT_NEAR(v.point().z(), z0 + 1.0, 1e-9) << "the sleep has 1 ms to go";
    EXPECT_TRUE(play.advance(v, 0, t0 + milliseconds(500))); // the second key; the wait for a pose begins
    EXPECT_NEAR(v.point().z(), z0 + 2.0, 1e-9);
    EXPECT_TRUE(play.advance(v, 0, t0 + milliseconds(1500)));
    EXPECT_NEAR(v.point().z(), z0 + 2.0, 1e-9) << "no pose yet";
    // A pose arrives: the third key, then q ends the script before the last key.
    EXPECT_FALSE(play.advance(v, 1, t0 + milliseconds(1600)));
    EXPECT_NEAR(v.point().z(), z0 + 3.0, 1e-9);
    EXPECT_FALSE(play.done());

    // Control: no pose within the wait's limit is a failure naming the script's line.
    ScriptPlayer lost(parseViewerScript("wait-pose 2\n", "ev.txt"), "ev.txt");
    EXPECT_TRUE(lost.advance(v, 4, t0));
    EXPECT_TRUE(lost.advance(v, 4, t0 + milliseconds(1999)));
    try {
        lost.advance(v, 4, t0 + milliseconds(2000));
        ADD_FAILURE() << "the wait did not time out";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("ev.txt:1: wait-pose: no needle pose within 2"), std::string::npos)
            << e.what();
    }
}

TEST_F(ViewerTest, WindowInputIsDeliveredToThePaneAndCloseEndsTheViewer)
{
    Viewer v(*mVolume, mOpt, test::table());
    const Vec3d p(mPhantom.centre.x(), -30, 20);
    const Vec2d w = windowPixel(v, ViewKind::Sagittal, p);
    WindowInput click;
    click.kind = WindowInput::Kind::Click;
    click.x = int(std::lround(w.x()));
    click.y = int(std::lround(w.y()));
    EXPECT_TRUE(deliver(v, click));
    EXPECT_TRUE(nearVec(v.point(), p, 0.5 * v.frame(ViewKind::Sagittal).pixelMm));
    WindowInput key;
    key.kind = WindowInput::Kind::Key;
    key.key = "Up";
    const double z = v.point().z();
    EXPECT_TRUE(deliver(v, key));
    EXPECT_NE(v.point(), p) << "the key reached the viewer";
    EXPECT_NEAR(std::abs(v.point().z() - z) + std::abs(v.point().x() - p.x()), 1.0, 1e-9)
        << "one slice in the pane last used";
    WindowInput close;
    close.kind = WindowInput::Kind::Close;
    EXPECT_FALSE(deliver(v, close));
    key.key = "q";
    EXPECT_FALSE(deliver(v, key));
}

TEST_F(ViewerTest, DistanceToolShowsItsLengthInTheStatus)
{
    Viewer v(*mVolume, mOpt, test::table());
    v.handle(key("d"));
    // 60 px apart along x and 80 along y on 0.5 mm pixels: 50 mm.
    v.handle(click(ViewKind::Axial, Vec2d(5, 2)));
    v.handle(click(ViewKind::Axial, Vec2d(65, 82)));
    EXPECT_NE(v.status().find("distance 50.0 mm"), std::string::npos) << v.status();
    // Saving with no path says so rather than writing an unreadable plan.
    v.handle(key("s"));
    EXPECT_NE(v.lastMessage().find("nothing to save"), std::string::npos);
    EXPECT_FALSE(std::filesystem::exists(mDir / "plan.json"));
}

TEST_F(ViewerTest, LiveNeedleIsDrawnWhereItsProjectionFalls)
{
    Viewer v(*mVolume, mOpt, test::table());
    // A vertical needle in the coronal plane through the crosshair (y = −12), away from the crosshair lines.
    const planning::NeedlePose needle{Vec3d(-10, mPhantom.centre.y(), 5), Vec3d(0, 0, -1), 90.0};
    const Vec3d onShaft(-10, mPhantom.centre.y(), 20);
    const Rgb colour = OverlayStyle{}.needle;
    const Image before = v.render();
    EXPECT_FALSE(colourNear(before, windowPixel(v, ViewKind::Coronal, onShaft), colour));
    v.setNeedle(needle);
    EXPECT_TRUE(v.dirty());
    const Image after = v.render();
    EXPECT_TRUE(colourNear(after, windowPixel(v, ViewKind::Coronal, onShaft), colour));
    EXPECT_TRUE(colourNear(after, windowPixel(v, ViewKind::Sagittal, onShaft), colour))
        << "and projected on the sagittal";
}

TEST_F(ViewerTest, ThreeDPaneUnderXvfbShowsTheVolumeAndTheNeedle)
{
    DisplayGuard display;
    if (!display.available()) GTEST_FAIL() << "no display for the 3D pane: " << display.why();
    mOpt.threeD = true;
    Viewer v(*mVolume, mOpt, test::table());
    const auto pane = [&](const Image& win) {
        const ViewFrame& f = v.frame(ViewKind::ThreeD);
        const Vec2d o = v.imageOrigin(ViewKind::ThreeD);
        Image p(f.width, f.height);
        for (int y = 0; y < f.height; ++y) {
            for (int x = 0; x < f.width; ++x) p.at(x, y) = win.at(int(o.x()) + x, int(o.y()) + y);
        }
        return p;
    };
    const Image first = pane(v.render());
    EXPECT_GT(test::greySpread(first), 5.0) << "blank 3D pane";
    v.setNeedle(planning::NeedlePose{Vec3d(-10, -12, 5), Vec3d(0, 0, -1), 90.0});
    const Image second = pane(v.render());
    // The shaft's projection (a parallel view from the front): orange, red well above blue.
    const Vec2d at = expectedPixel("3d", Vec3d(-10, -12, 20), mLo, mHi, v.frame(ViewKind::ThreeD).pixelMm);
    bool found = false;
    for (int dx = -2; dx <= 2 && !found; ++dx) { // a 3 px line, placed by GL to within a pixel
        const Rgb p = second.at(int(std::lround(at.x())) + dx, int(std::lround(at.y())));
        found =
            p.r > 200 && p.r > p.b + 100 && !(p == first.at(int(std::lround(at.x())) + dx, int(std::lround(at.y()))));
    }
    EXPECT_TRUE(found) << "no needle at the projected shaft";
}

} // namespace
} // namespace voxhap::render
