// SPDX-License-Identifier: Apache-2.0
/// @file TestCliView.cpp
/// @brief `voxhap view` as a user (or a script) runs it: clicks in a pane write
/// the plan at the clicked world points, the snapshot has the size asked for
/// and shows the path and a streamed needle where the projection puts them;
/// the X window path runs and quits under Xvfb; `voxhap serve --viewer`
/// streams poses to a listener; bad input gets one line.

#include "common/CliRunner.h"
#include "common/Tolerances.h"

#include "haptic/igtl/PoseStream.h"
#include "planning/PlanFile.h"
#include "render/raster/ImageFile.h"
#include "render/views/Overlays.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

namespace {

namespace fs = std::filesystem;

using voxhap::Vec3d;
using voxhap::render::Image;
using voxhap::render::Rgb;
using voxhap::render::Vec2d;
using Result = voxhap::test::CliResult;

// `voxhap phantom sphere --spacing 1`: x, z in −25..25, y in −40..5 [mm, LPS].
const Vec3d kViewLo(-25, -40, -25), kViewHi(25, 5, 25);

// With --size 204x228 the panes are 100 × 100 px, and the largest side of the
// box (50 mm) fills one: 0.5 mm pixels.
constexpr double kViewPixelMm = 0.5;
const char* const kViewSize = "--size 204x228";

/// The pixel of world point @p p in a pane image over the phantom's box
/// (radiological convention, closed form).
Vec2d viewPixel(const std::string& view, const Vec3d& p)
{
    const auto at = [](double fromEdgeMm) { return fromEdgeMm / kViewPixelMm - 0.5; };
    if (view == "axial") return {at(p.x() - kViewLo.x()), at(p.y() - kViewLo.y())};
    if (view == "sagittal") return {at(p.y() - kViewLo.y()), at(kViewHi.z() - p.z())};
    return {at(p.x() - kViewLo.x()), at(kViewHi.z() - p.z())}; // coronal, 3d
}

/// The window pixel of @p p in pane @p view, placed as the viewer reports (--json).
Vec2d viewWindowPixel(const nlohmann::json& j, const std::string& view, const Vec3d& p)
{
    for (const auto& pane : j["panes"]) {
        if (pane["view"] == view) {
            EXPECT_EQ(pane["pixel_mm"].get<double>(), kViewPixelMm);
            return Vec2d(pane["image_origin"][0].get<int>(), pane["image_origin"][1].get<int>()) + viewPixel(view, p);
        }
    }
    ADD_FAILURE() << "no pane " << view;
    return {0, 0};
}

/// True if a pixel within 1 px of @p at has exactly colour @p c (lines snap to pixels).
bool viewColourNear(const Image& img, const Vec2d& at, Rgb c)
{
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            const int x = int(std::lround(at.x())) + dx, y = int(std::lround(at.y())) + dy;
            if (img.contains(x, y) && img.at(x, y) == c) return true;
        }
    }
    return false;
}

double viewGreySpread(const Image& img, int x0, int y0, int x1, int y1)
{
    double s = 0, s2 = 0, n = 0;
    for (int y = y0; y < y1; ++y) {
        for (int x = x0; x < x1; ++x) {
            const Rgb p = img.at(x, y);
            const double g = (p.r + p.g + p.b) / 3.0;
            s += g, s2 += g * g, n += 1;
        }
    }
    return std::sqrt(std::max(0.0, s2 / n - (s / n) * (s / n)));
}

class CliView : public voxhap::test::CliTest {
protected:
    void SetUp() override
    {
        CliTest::SetUp();
        const Result r = run("phantom sphere --sphere-tissue cortical_bone --spacing 1 -o s.vdb");
        ASSERT_EQ(r.exitCode, 0) << r.err;
    }
    void write(const std::string& name, const std::string& text) const { std::ofstream(mDir / name) << text; }
    /// Whole pixels of the axial pane for a world point, as a mouse clicks them.
    static std::string axialClick(const Vec3d& p)
    {
        const Vec2d px = viewPixel("axial", p);
        std::ostringstream os;
        os << "click axial " << std::lround(px.x()) << ' ' << std::lround(px.y()) << '\n';
        return os.str();
    }
    /// `view --listen` on a free port, its snapshot @p png taken once a pose came,
    /// while this thread sends @p pose every 20 ms until the viewer has ended.
    Result viewWhileStreaming(const std::string& png, const voxhap::haptic::StreamedPose& pose)
    {
        int port = 0;
        {
            voxhap::haptic::PoseReceiver probe(0); // a free port, released for the viewer
            port = probe.port();
        }
        write("wait.txt", "wait-pose 30\n");
        Result r;
        std::atomic<bool> done{false};
        std::thread viewer([&] {
            r = run("view s.vdb --no-3d --listen " + std::to_string(port) + " --script wait.txt --snapshot " + png +
                " " + std::string(kViewSize) + " --point 0,-20,0 --json");
            done = true;
        });
        voxhap::haptic::PoseSender tx("127.0.0.1", port, 0.05);
        while (!done) {
            tx.send(pose);
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        }
        viewer.join();
        return r;
    }
    // The axial slice through the crosshair (--point 0,-20,0): z = 0.
    const Vec3d mEntry{-15, -35, 0}, mTarget{0, -20, 0};
};

TEST_F(CliView, ScriptedClicksWriteThePlanAndASnapshot)
{
    write("ev.txt", "key p\n" + axialClick(mEntry) + axialClick(mTarget) + "key s\n");
    const Result r = run("view s.vdb --script ev.txt --snapshot shot.png --save plan.json " + std::string(kViewSize) +
        " "
        "--point 0,-20,0 --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    const auto plan = voxhap::planning::loadPlan(mDir / "plan.json");
    ASSERT_EQ(plan.paths.size(), 1u);
    // A click lands on a pixel centre: within half a 0.5 mm pixel, so within half a 1 mm voxel, of the point aimed at.
    EXPECT_TRUE(voxhap::test::nearVec(plan.paths[0].entry, mEntry, voxhap::test::halfVoxel(1.0)));
    EXPECT_TRUE(voxhap::test::nearVec(plan.paths[0].target, mTarget, voxhap::test::halfVoxel(1.0)));

    const Image shot = voxhap::render::readImage(mDir / "shot.png");
    EXPECT_EQ(shot.width(), 204);
    EXPECT_EQ(shot.height(), 228);
    EXPECT_GT(viewGreySpread(shot, 0, 0, shot.width(), shot.height()), 5.0) << "blank snapshot";
    // The path in the axial pane, where its projection falls; between the entry
    // and target rings (5 px radius on a 42 px path), which cover the path's ends.
    const Rgb path = voxhap::render::OverlayStyle{}.path;
    const Vec3d a = plan.paths[0].entry, b = plan.paths[0].target;
    for (double t : {0.35, 0.5, 0.65}) {
        EXPECT_TRUE(viewColourNear(shot, viewWindowPixel(j, "axial", a + t * (b - a)), path)) << t;
    }
    // The 3D pane (Xvfb when there is no display) shows the volume.
    const auto& p3 = j["panes"][3];
    ASSERT_EQ(p3["view"], "3d");
    const int x0 = p3["image_origin"][0], y0 = p3["image_origin"][1];
    EXPECT_GT(
        viewGreySpread(shot, x0, y0, x0 + p3["image_size"][0].get<int>(), y0 + p3["image_size"][1].get<int>()), 5.0)
        << "blank 3D pane";
}

TEST_F(CliView, ScriptedDragTurnsThe3dPaneAndResetRestoresIt)
{
    // Three snapshots of the same viewer: untouched, after a drag (the camera
    // turned), and after the same drag followed by r (the camera reset). The
    // snapshot is drawn at full quality (the drag released), so the reset one
    // is pixel-identical to the untouched one and the turned one is not.
    write("none.txt", "key n\n");
    write("turn.txt", "drag 3d 30 0\ndrag 3d 15 10\nrelease\n");
    write("reset.txt", "drag 3d 30 0\ndrag 3d 15 10\nrelease\nscroll 3d 2\nkey r\n");
    nlohmann::json j;
    std::vector<Image> shots;
    for (const std::string name : {"none", "turn", "reset"}) {
        const Result r = run("view s.vdb --script " + name + ".txt --snapshot " + name + ".png " + kViewSize +
            " --point 0,-20,0 --json");
        ASSERT_EQ(r.exitCode, 0) << name << ": " << r.err;
        j = nlohmann::json::parse(r.out);
        shots.push_back(voxhap::render::readImage(mDir / (name + ".png")));
    }
    const auto& p3 = j["panes"][3];
    ASSERT_EQ(p3["view"], "3d");
    const int x0 = p3["image_origin"][0], y0 = p3["image_origin"][1];
    const int w = p3["image_size"][0], h = p3["image_size"][1];
    const auto differing = [&](const Image& a, const Image& b) {
        long n = 0;
        for (int y = y0; y < y0 + h; ++y) {
            for (int x = x0; x < x0 + w; ++x) n += !(a.at(x, y) == b.at(x, y));
        }
        return n;
    };
    EXPECT_GT(differing(shots[0], shots[1]), long(w) * h / 20) << "a 45 degree turn changes the 3D pane";
    EXPECT_EQ(differing(shots[0], shots[2]), 0) << "r restores the first camera";
    // The slices do not follow the 3D camera.
    const auto& p0 = j["panes"][0];
    const int ax = p0["image_origin"][0], ay = p0["image_origin"][1];
    for (int y = ay; y < ay + p0["image_size"][1].get<int>(); ++y) {
        for (int x = ax; x < ax + p0["image_size"][0].get<int>(); ++x)
            ASSERT_TRUE(shots[0].at(x, y) == shots[1].at(x, y)) << x << "," << y;
    }
    const Result help = run("view --help");
    EXPECT_NE(help.out.find("drag rotates"), std::string::npos) << help.out;
    EXPECT_NE(help.out.find("r resets"), std::string::npos);
}

TEST_F(CliView, WindowRunsUnderXvfbAndQuitsFromTheScript)
{
    write("ev.txt", "key p\n" + axialClick(mEntry) + axialClick(mTarget) + "key s\nkey q\n");
    const Result r = run("view s.vdb --no-3d --script ev.txt --save w.json " + std::string(kViewSize) +
            " --point 0,-20,0 --timeout 60 --json",
        "xvfb-run -a -s '-screen 0 640x480x24'");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["ended"], "quit") << "the script's q, not the timeout";
    EXPECT_GE(j["frames"].get<int>(), 1);
    const auto plan = voxhap::planning::loadPlan(mDir / "w.json");
    ASSERT_EQ(plan.paths.size(), 1u);
    EXPECT_TRUE(voxhap::test::nearVec(plan.paths[0].target, mTarget, voxhap::test::halfVoxel(1.0)));
}

TEST_F(CliView, StreamedNeedleIsDrawnInTheSnapshot)
{
    // A vertical needle in the coronal plane through the crosshair (y = −20).
    const Result r = viewWhileStreaming("n.png", {Vec3d(-10, -20, 0), Vec3d(0, 0, -1), {}});
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_GE(j["poses"].get<int>(), 1);
    const Image shot = voxhap::render::readImage(mDir / "n.png");
    const Rgb needle = voxhap::render::OverlayStyle{}.needle;
    EXPECT_TRUE(viewColourNear(shot, viewWindowPixel(j, "coronal", Vec3d(-10, -20, 15)), needle));
    EXPECT_FALSE(viewColourNear(shot, viewWindowPixel(j, "coronal", Vec3d(10, -20, 15)), needle))
        << "and not elsewhere";
}

TEST_F(CliView, StreamedBentNeedleIsDrawnAlongItsShaft)
{
    // The hub straight above x = −10 as before, the shaft turning at z = 30 to a tip at x = +10
    // in the coronal plane; the pose's straight line (x = −10 down to z = 0) is not the needle.
    const Result r = viewWhileStreaming(
        "b.png", {Vec3d(-10, -20, 0), Vec3d(0, 0, -1), {Vec3d(-10, -20, 90), Vec3d(-10, -20, 30), Vec3d(10, -20, 0)}});
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    const Image shot = voxhap::render::readImage(mDir / "b.png");
    const Rgb needle = voxhap::render::OverlayStyle{}.needle;
    // Off the crosshair (x = 0), which is drawn over the needle.
    EXPECT_TRUE(viewColourNear(shot, viewWindowPixel(j, "coronal", Vec3d(-5, -20, 22.5)), needle)) << "on the bend";
    EXPECT_FALSE(viewColourNear(shot, viewWindowPixel(j, "coronal", Vec3d(-10, -20, 10)), needle))
        << "control: the straight line of the pose is not drawn";
}

TEST_F(CliView, ServeStreamsTheBentShaftOfABendingScene)
{
    voxhap::haptic::PoseReceiver rx(0);
    const Result r =
        run("serve --scene lumbar-puncture-bending --device sim --speed 50 --out bent --json --viewer 127.0.0.1:" +
            std::to_string(rx.port()));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto pose = rx.latest();
    ASSERT_TRUE(pose.has_value());
    ASSERT_GE(pose->shaft.size(), 2u) << "a bending needle's pose carries its shaft";
    // The hub is clamped to the device's pose (physics.md §9): the shaft starts where the
    // streamed straight needle's hub is, 90 mm behind its tip (to the float32 the
    // wire carries, 1e-5 mm here), and bends away from that line toward its tip.
    EXPECT_LT((pose->shaft.front() - (pose->tip - 90.0 * pose->direction)).norm(), 1e-3);
    const Vec3d off = pose->shaft.back() - pose->shaft.front();
    // A floor far under the millimetres a 22 G needle bends (guide chapter 10); straight is 0.
    EXPECT_GT((off - off.dot(pose->direction) * pose->direction).norm(), 0.01) << "the shaft bends";
}

TEST_F(CliView, ServeStreamsTheNeedleToAViewer)
{
    voxhap::haptic::PoseReceiver rx(0);
    // -5 to 60 mm at 50 mm/s: about 1.3 s of real time.
    const Result r = run("serve --scene senac-average --device sim --speed 50 --out served --json --viewer 127.0.0.1:" +
        std::to_string(rx.port()));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    ASSERT_GE(rx.poses(), 1);
    const auto pose = rx.latest();
    ASSERT_TRUE(pose.has_value());
    EXPECT_TRUE(pose->shaft.empty()) << "a straight needle streams no shaft";
    // The pose streamed is one the servo loop recorded: find it in session.csv.
    // The wire holds float32 (6e-6 mm at 100 mm) and the CSV 10 digits: 1e-4 mm covers both.
    constexpr double kStreamMm = 1e-4;
    std::ifstream csv(mDir / "served" / "session.csv");
    std::string line;
    std::getline(csv, line);
    bool found = false;
    while (!found && std::getline(csv, line)) {
        std::istringstream in(line);
        std::string cell;
        double v[7];
        for (double& x : v) {
            std::getline(in, cell, ',');
            x = std::stod(cell);
        }
        found = voxhap::test::nearVec(Vec3d(v[1], v[2], v[3]), pose->tip, kStreamMm) &&
            voxhap::test::nearVec(Vec3d(v[4], v[5], v[6]), pose->direction, kStreamMm);
    }
    EXPECT_TRUE(found) << "the streamed tip " << pose->tip.transpose() << " is no recorded pose";
    voxhap::test::expectUsageError(
        run("serve --scene senac-average --device sim --viewer 127.0.0.1:99999"), "--viewer");
}

TEST_F(CliView, RefusesWithOneLine)
{
    write("bad.txt", "key p\nclick axial 3\n");
    voxhap::test::expectFailure(run("view s.vdb --script bad.txt --snapshot x.png"), "bad.txt:2: missing y");
    EXPECT_FALSE(fs::exists(mDir / "x.png"));
    voxhap::test::expectUsageError(run("view s.vdb --snapshot x.png --size 10x10"), "--size");
    voxhap::test::expectUsageError(run("view s.vdb --snapshot x.png --size wide"), "--size");
    voxhap::test::expectUsageError(run("view s.vdb --snapshot x.png --listen 70000"), "--listen");
    voxhap::test::expectUsageError(run("view s.vdb --snapshot x.png --mode xray"), "unknown mode 'xray'");
    voxhap::test::expectUsageError(run("view s.vdb --no-3d --snapshot x.png --point 999,0,0"), "--point");
    voxhap::test::expectFailure(run("view s.vdb", "env -u DISPLAY"), "no X display");
    write("wait.txt", "wait-pose 0.2\n");
    voxhap::test::expectFailure(run("view s.vdb --no-3d --script wait.txt --snapshot x.png"), "wait.txt:1: wait-pose");
    voxhap::test::expectFailure(run("view missing.vdb --no-3d --snapshot x.png"), "missing.vdb");
    write("save.txt", "key p\nclick axial 10 10\nclick axial 20 20\nkey s\n");
    voxhap::test::expectFailure(
        run("view s.vdb --no-3d --script save.txt --save nodir/p.json --snapshot x.png"), "nodir/p.json");
}

} // namespace
