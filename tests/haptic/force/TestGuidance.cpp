// SPDX-License-Identifier: Apache-2.0
/// @file TestGuidance.cpp
/// @brief The guidance fixture (issue 23 item 2): zero on the planned line,
/// the closed form f(r) = min(k·r, F_max) perpendicular to it with its taper and
/// fade-out, no axial push, passivity round closed loops (physics.md §6.1, §6.4),
/// and off by default.

#include "common/BuiltinTable.h"

#include "core/Errors.h"
#include "haptic/force/Guidance.h"
#include "haptic/scene/Scene.h"
#include "haptic/scene/ScriptedInsertion.h"

#include <Eigen/Geometry> // for cross and unitOrthogonal
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <random>

namespace voxhap::haptic {
namespace {

using voxhap::test::table;

/// The projection onto the line leaves round-off of ~1e-15 mm on points built on
/// it; at k = 0.2 N/mm that is ~1e-16 N. Far below anything a device renders.
constexpr double kOnLineN = 1e-12;
/// Closed forms evaluated in the same arithmetic: a few ulps of ~1 N.
constexpr double kClosedFormN = 1e-12;
/// Round-off of Σ F·Δx over ~1e5 ticks (as TestPassivity.cpp).
constexpr double kRoundOffNmm = 1e-9;

const GuideLine kLine{Vec3d(10.0, 5.0, -3.0), Vec3d(-20.0, -70.0, 12.0)};

TEST(Guidance, ZeroForceOnThePlannedLine)
{
    Guidance g(GuidanceParams{}, kLine);
    const Vec3d w = (kLine.target - kLine.entry).normalized();
    for (double s = -30.0; s <= 120.0; s += 0.37) { // outside the skin, at the entry, inside, past the target
        EXPECT_LE(g.update(kLine.entry + s * w, 0.001 * s).norm(), kOnLineN) << s;
    }
    EXPECT_EQ(g.update(kLine.entry, 0.0), Vec3d::Zero());
}

TEST(Guidance, PerpendicularSpringWithSaturationTaperAndFadeOut)
{
    GuidanceParams p;
    p.stiffnessNPerMm = 0.2;
    p.maxForceN = 1.0;
    Guidance g(p, kLine);
    const Vec3d w = (kLine.target - kLine.entry).normalized();
    const Vec3d a = w.unitOrthogonal(), b = w.cross(a);
    for (const double r : {0.1, 2.0, 4.9, 5.0, 12.0, 80.0}) {
        for (const double s : {-10.0, 0.0, 40.0}) {
            const Vec3d side = (std::cos(r) * a + std::sin(r) * b).normalized();
            const Vec3d f = g.update(kLine.entry + s * w + r * side, 0.0);
            EXPECT_NEAR(f.norm(), std::min(0.2 * r, 1.0), kClosedFormN) << r;
            EXPECT_NEAR(f.dot(w), 0.0, kClosedFormN) << "no push along the line";
            EXPECT_NEAR(f.normalized().dot(-side), 1.0, 1e-12) << "toward the line";
        }
    }
    // Capture radius R: full force to R, linear to zero at 2R, nothing beyond.
    p.captureRadiusMm = 10.0;
    Guidance tapered(p, kLine);
    EXPECT_NEAR(tapered.profileN(10.0), 1.0, kClosedFormN);
    EXPECT_NEAR(tapered.profileN(15.0), 0.5, kClosedFormN);
    EXPECT_EQ(tapered.profileN(20.0), 0.0);
    EXPECT_EQ(tapered.profileN(50.0), 0.0);
    EXPECT_NEAR(tapered.stiffestNPerMm(), 0.2, 0.0);
    // Fade-out over 10 s from the first tick (at t = 3 s here): half at 8 s, none at 13 s.
    p.captureRadiusMm = 0.0;
    p.fadeOutS = 10.0;
    Guidance fading(p, kLine);
    const Vec3d off = kLine.entry + 2.0 * a;
    EXPECT_NEAR(fading.update(off, 3.0).norm(), 0.4, kClosedFormN);
    EXPECT_NEAR(fading.update(off, 8.0).norm(), 0.2, kClosedFormN);
    EXPECT_EQ(fading.update(off, 13.0).norm(), 0.0);
    EXPECT_EQ(fading.update(off, 100.0).norm(), 0.0);
}

/// The work a force field does on the hand round a closed loop that starts and ends
/// at one point (zero-order hold: F_n·(x_{n+1} − x_n)), and the sampled field's leak
/// ½·K·|Δx|² summed over the ticks: a random walk, then circles round the line at
/// radii 2 and 5 mm, ten turns each (where a field with a curl does work every
/// turn), then home.
struct LoopWork {
    double work = 0, leak = 0;
};
template <typename Field> LoopWork closedLoop(Field field, double stiffest)
{
    std::mt19937 rng(5);
    std::normal_distribution<double> n(0.0, 1.0);
    const Vec3d w = (kLine.target - kLine.entry).normalized();
    const Vec3d a = w.unitOrthogonal(), b = w.cross(a);
    const Vec3d centre = kLine.entry + 20.0 * w;
    const Vec3d home = centre + Vec3d(1.0, 1.0, 1.0);
    Vec3d x = home;
    double t = 0.0;
    LoopWork r;
    Vec3d f = field(x, t);
    const auto move = [&](const Vec3d& to) {
        r.work += f.dot(to - x);
        r.leak += 0.5 * stiffest * (to - x).squaredNorm();
        x = to;
        t += 1e-3;
        f = field(x, t);
    };
    const auto straight = [&](const Vec3d& to, int steps) {
        const Vec3d from = x;
        for (int i = 1; i <= steps; ++i) move(from + (double(i) / steps) * (to - from));
    };
    for (int i = 0; i < 100000; ++i) move(x + 0.02 * Vec3d(n(rng), n(rng), n(rng)));
    for (const double radius : {2.0, 5.0}) {
        straight(centre + radius * a, 5000);
        for (int turn = 0; turn < 10; ++turn) {
            for (int i = 1; i <= 2000; ++i) {
                const double phi = 2.0 * M_PI * i / 2000.0;
                move(centre + radius * (std::cos(phi) * a + std::sin(phi) * b));
            }
        }
    }
    straight(home, 5000);
    return r;
}

// The field depends on r alone: round a closed loop it returns at most the sampled
// field's leak, ½·K·Δx² a tick (Guidance.h), also while it fades. K is the field's
// steepest slope from the parameters, not from the code: the spring k up to F_max,
// and with a capture radius R the taper from f(R) = min(k·R, F_max) to 0 over R.
// The control adds a swirl about the line, 0.05 N/mm × r tangential, a field that
// is not conservative (its curl is along the line): the same loop gains energy
// from it, 2π·0.05·r² N·mm a turn, far beyond the leak, and the check fails it.
TEST(Guidance, ClosedLoopsCreateNoEnergy)
{
    for (const double fade : {0.0, 20.0}) {
        GuidanceParams p;
        p.captureRadiusMm = 6.0; // a taper, so its slope counts toward K too
        p.fadeOutS = fade;
        const double K = std::max(
            p.stiffnessNPerMm, std::min(p.stiffnessNPerMm * p.captureRadiusMm, p.maxForceN) / p.captureRadiusMm);
        EXPECT_DOUBLE_EQ(K, 0.2); // k = 0.2 N/mm; the taper 1 N over 6 mm is gentler
        Guidance g(p, kLine);
        const LoopWork passive = closedLoop([&](const Vec3d& x, double t) { return g.update(x, t); }, K);
        SCOPED_TRACE(fade);
        EXPECT_LE(passive.work, passive.leak + kRoundOffNmm);
        EXPECT_GT(passive.leak, 0.0);

        Guidance h(p, kLine);
        const Vec3d w = h.direction();
        const double swirl = 0.05; // N/mm
        const LoopWork active = closedLoop(
            [&](const Vec3d& x, double t) {
                const Vec3d r = h.offset(x);
                return Vec3d(h.update(x, t) + swirl * w.cross(r));
            },
            K + swirl);
        EXPECT_GT(active.work, active.leak + 1.0) << "the control: a field with a curl must fail the check";
    }
}

// Off by default; on, toward the scene's own path, an insertion along it feels
// nothing from the fixture and renders what it did without.
TEST(Guidance, OffByDefaultAndSilentOnThePath)
{
    EXPECT_FALSE(loadScene("senac-average").terms.guidance.on);
    std::ifstream in(VOXHAP_SOURCE_DIR "/data/scenes/senac-average.json");
    nlohmann::json j = nlohmann::json::parse(in);
    j["terms"]["guidance"] = {{"stiffness_N_per_mm", 0.3}, {"max_force_N", 2.0}};
    const SceneInstance guided(parseScene(j.dump(), "guided.json"), nullptr, table());
    EXPECT_TRUE(guided.scene().terms.guidance.on);
    const SceneInstance plain(loadScene("senac-average"), nullptr, table());
    auto a = plain.makeModel();
    auto b = guided.makeModel();
    const InsertionScript script = InsertionScript::constantSpeed(-5.0, 30.0, 2.0);
    const InsertionResult ra = runInsertion(*a, script, 1000.0), rb = runInsertion(*b, script, 1000.0);
    ASSERT_EQ(ra.rows.size(), rb.rows.size());
    for (std::size_t i = 0; i < ra.rows.size(); ++i)
        ASSERT_LE((ra.rows[i].force - rb.rows[i].force).norm(), kOnLineN) << "tick " << i;
    EXPECT_TRUE(rb.summary.guidance);
    EXPECT_LE(rb.summary.peakGuidanceN, kOnLineN);

    // A planned line 1.5 mm beside the path: the insertion is pulled toward it by
    // k·1.5 mm at every tick, perpendicular to the path.
    const Vec3d side = 1.5 * Vec3d(1.0, 0.0, 0.0);
    auto c = guided.makeModel(GuideLine{guided.entry() + side, guided.target() + side});
    const InsertionResult rc = runInsertion(*c, script, 1000.0);
    EXPECT_NEAR(rc.summary.peakGuidanceN, 0.3 * 1.5, kClosedFormN);
    EXPECT_NEAR(rc.summary.maxOffsetMm, 1.5, 1e-12);
    EXPECT_EQ(rc.summary.pops, ra.summary.pops) << "the axial profile is the tissue's alone";

    EXPECT_THROW(Guidance(GuidanceParams{}, GuideLine{Vec3d::Zero(), Vec3d::Zero()}), ValueError);
}

} // namespace
} // namespace voxhap::haptic
