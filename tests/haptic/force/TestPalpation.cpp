// SPDX-License-Identifier: Apache-2.0
/// @file TestPalpation.cpp
/// @brief Palpation before insertion (issue 23 item 1) on the lumbar phantom: the
/// skin map against the phantom's analytic layers, the force over a spinous
/// process against the interspace at the same indentation (k = E·A/T, closed
/// form), the god-object never passing the skin, passivity round closed loops
/// (physics.md §6.1, §6.4), and the hand-over to the needle at the entry.

#include "common/BuiltinTable.h"

#include "core/Errors.h"
#include "haptic/force/NeedleForceModel.h"
#include "haptic/scene/Scene.h"
#include "haptic/scene/ScriptedInsertion.h"
#include "phantoms/Phantoms.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>

namespace voxhap::haptic {
namespace {

using voxhap::test::table;
using Json = nlohmann::json;

/// The phantom's voxel size in these scenes [mm].
constexpr double kSpacingMm = 0.5;
/// E·A of the test scene: 30 kPa over 100 mm² = 3 N.
constexpr double kEAN = 3.0;
/// The bisection places a label face to 1e-12 mm (Palpation.cpp); the skin and the
/// spinous process's top lie on voxel faces of the phantom (multiples of 0.5 mm).
constexpr double kFaceMm = 1e-9;
/// A boundary off the voxel faces (the canal's floor at 57.4 mm) is where the voxel
/// centres change label: within half a voxel of the analytic one.
constexpr double kHalfVoxelMm = 0.5 * kSpacingMm;
/// Round-off of Σ F·Δx over ~1e5 ticks of forces up to a few N (as TestPassivity.cpp).
constexpr double kRoundOffNmm = 1e-9;

/// senac-average with palpation on (entry radius 1 mm, k_max 0.5 N/mm) and @p extra
/// merged into the palpation block.
Json palpationScene(const Json& extra = Json::object())
{
    std::ifstream in(VOXHAP_SOURCE_DIR "/data/scenes/senac-average.json");
    Json j = Json::parse(in);
    j["name"] = "palpation-test";
    Json p = {{"entry_radius_mm", 1.0}, {"modulus_kPa", 30.0}, {"contact_area_mm2", 100.0},
        {"max_stiffness_N_per_mm", 0.5}, {"min_stiffness_N_per_mm", 0.02}, {"radius_mm", 35.0}};
    p.update(extra);
    j["terms"]["palpation"] = p;
    return j;
}

const SceneInstance& instance()
{
    static const SceneInstance inst(parseScene(palpationScene().dump(), "palpation.json"), nullptr, table());
    return inst;
}

/// The first rigid span along −y from the skin at (x, 0, z) in the analytic model [mm].
double analyticBoneDepth(double x, double z)
{
    const volume::PhantomModel m = volume::lumbarModel(volume::LumbarParams{}, table());
    for (const volume::LayerSpan& s :
        volume::traceLayers(m.classify, Vec3d(x, 0.0, z), Vec3d(0.0, -1.0, 0.0), 100.0, table())) {
        if (table().at(s.tissue).rigid) return s.startMm;
    }
    return std::numeric_limits<double>::infinity();
}

// Points on the phantom's back [mm, LPS; skin at y = 0, body at y < 0]: the top of
// the lower spinous process (midline, z = 20) and the interspace beside the entry
// (midline, z = 3: between the processes, |z| < 6, and over the vertebral body).
const Vec3d kSpinous(0.0, 0.0, 20.0);
const Vec3d kInterspace(0.0, 0.0, 3.0);
const Vec3d kDown(0.0, -1.0, 0.0);

/// Drives a force model with the needle held along the path (−y) and books the work
/// done on the hand, Σ F_n·(x_{n+1} − x_n) (zero-order hold), with the sampled
/// spring's own leak ½·k·Δx² (Palpation.h) as the bound.
class Hand {
public:
    explicit Hand(const SceneInstance& inst, const Vec3d& start)
        : mModel(inst.makeModel()), mK(inst.skinMap()->maxStiffness())
    {
        move(start);
    }
    void move(const Vec3d& tip)
    {
        if (mHave) {
            const Vec3d dx = tip - mTip;
            mWork += mOut.modelForce.dot(dx);
            mLeak += 0.5 * mK * dx.squaredNorm();
        }
        NeedleInput in;
        in.timeS = mT;
        in.dtS = 1e-3;
        in.tip = tip;
        in.direction = kDown;
        in.velocity = mHave ? Vec3d((tip - mTip) / 1e-3) : Vec3d::Zero();
        mModel->step(in, mOut);
        for (const Event& e : mOut.events) mEvents.push_back(e.type);
        mTip = tip;
        mHave = true;
        mT += 1e-3;
    }
    /// Straight to @p to in steps of at most @p step mm.
    void line(const Vec3d& to, double step)
    {
        const Vec3d from = mTip;
        const int n = std::max(1, int(std::ceil((to - from).norm() / step)));
        for (int i = 1; i <= n; ++i) move(from + (double(i) / n) * (to - from));
    }
    const NeedleOutput& out() const { return mOut; }
    double work() const { return mWork; }
    double leak() const { return mLeak; }
    bool saw(EventType t) const { return std::find(mEvents.begin(), mEvents.end(), t) != mEvents.end(); }
    const NeedleForceModel& model() const { return *mModel; }

private:
    std::unique_ptr<NeedleForceModel> mModel;
    double mK, mT = 0.0, mWork = 0.0, mLeak = 0.0;
    bool mHave = false;
    Vec3d mTip = Vec3d::Zero();
    NeedleOutput mOut;
    std::vector<EventType> mEvents;
};

TEST(Palpation, SkinMapFindsTheSkinAndTheBoneOfThePhantom)
{
    const SkinMap& map = *instance().skinMap();
    EXPECT_TRUE(map.fromLabels());
    for (const Vec3d& w : {kSpinous, kInterspace, Vec3d(15.0, 0.0, -20.0)}) {
        const Vec3d m = map.toMap(w);
        const SkinSample s = map.sample(m.x(), m.y());
        ASSERT_TRUE(s.surface) << w.transpose();
        EXPECT_NEAR(s.skinMm, 0.0, kFaceMm) << w.transpose(); // the skin at y = 0
    }
    // Soft tissue over bone: the spinous process's top (skin 2 + fat 8 + supraspinous
    // 3 = 13 mm, on voxel faces) and the vertebral body under the interspace (57.4 mm,
    // off the faces), from the analytic phantom.
    const double tSpinous = analyticBoneDepth(kSpinous.x(), kSpinous.z());
    const double tInter = analyticBoneDepth(kInterspace.x(), kInterspace.z());
    EXPECT_NEAR(tSpinous, 13.0, 1e-6);
    const Vec3d ms = map.toMap(kSpinous), mi = map.toMap(kInterspace);
    EXPECT_NEAR(map.sample(ms.x(), ms.y()).thicknessMm, tSpinous, kFaceMm);
    EXPECT_NEAR(map.sample(mi.x(), mi.y()).thicknessMm, tInter, kHalfVoxelMm);
    // Paraspinal muscle at x = 30 has no bone within reach: k_min.
    const Vec3d mm = map.toMap(Vec3d(30.0, 0.0, 20.0));
    EXPECT_FALSE(std::isfinite(map.sample(mm.x(), mm.y()).thicknessMm));
    EXPECT_DOUBLE_EQ(map.sample(mm.x(), mm.y()).stiffnessNPerMm, 0.02);
}

// The closed form: k(T) = E·A/T within [k_min, k_max], F = k·δ straight out of the
// skin (flat skin, k uniform around both points, so the proxy stays above the tip).
TEST(Palpation, SpinousProcessIsStifferThanTheInterspaceByTheRatioOfTissueDepths)
{
    const double tSpinous = analyticBoneDepth(kSpinous.x(), kSpinous.z());
    const double tInter = analyticBoneDepth(kInterspace.x(), kInterspace.z());
    for (const double delta : {0.5, 2.0, 4.0}) {
        Vec3d force[2];
        const Vec3d at[2] = {kSpinous, kInterspace};
        for (int k = 0; k < 2; ++k) {
            Hand hand(instance(), at[k] + Vec3d(0.0, 5.0, 0.0)); // 5 mm above the skin
            hand.line(at[k] + delta * kDown, 0.01);
            ASSERT_TRUE(hand.out().palpating);
            ASSERT_TRUE(hand.out().palpation.contact);
            EXPECT_EQ(hand.out().events.size(), 0);
            EXPECT_EQ(hand.out().axialN, 0.0); // the needle's layers wait
            force[k] = hand.out().modelForce;
        }
        // T is exact over the process; over the interspace within half a voxel, so
        // k within E·A·(h/2)/T², F within δ times that.
        const double slack = delta * kEAN * kHalfVoxelMm / (tInter * tInter);
        EXPECT_NEAR(force[0].y(), kEAN / tSpinous * delta, 1e-9) << delta;
        EXPECT_NEAR(force[1].y(), kEAN / tInter * delta, slack) << delta;
        EXPECT_NEAR(force[0].x(), 0.0, 1e-12);
        EXPECT_NEAR(force[0].z(), 0.0, 1e-12);
        EXPECT_GT(force[0].y() / force[1].y(), 4.0) << "the process must stand out from the interspace";
    }
}

TEST(Palpation, TheProxyNeverPassesTheSkin)
{
    const SkinMap& map = *instance().skinMap();
    const auto onSkin = [&](const NeedleOutput& o) {
        const Vec3d m = map.toMap(o.palpation.proxy);
        return std::abs(m.z() - map.sample(m.x(), m.y()).skinMm);
    };
    for (const Vec3d& at : {kSpinous, kInterspace, Vec3d(12.0, 0.0, -25.0)}) {
        Hand hand(instance(), at + Vec3d(0.0, 5.0, 0.0));
        hand.line(at, 0.05);
        double last = 0.0;
        for (double d = 0.05; d <= 80.0; d += 0.05) { // far deeper than any finger presses
            hand.move(at + d * kDown);
            const NeedleOutput& o = hand.out();
            ASSERT_TRUE(o.palpating && o.palpation.contact) << d;
            ASSERT_LE(onSkin(o), 1e-9) << "proxy off the skin at depth " << d;
            ASSERT_GE(o.modelForce.y(), last) << "the push out fell at depth " << d; // no pop-through
            last = o.modelForce.y();
        }
        // A fast sweep across processes and interspaces 20 mm deep: 0.5 mm a tick.
        for (double z = at.z(); z <= 30.0; z += 0.5) {
            hand.move(Vec3d(at.x(), -20.0, z));
            ASSERT_TRUE(hand.out().palpation.contact);
            ASSERT_LE(onSkin(hand.out()), 1e-9) << "z " << z;
            ASSERT_GT(hand.out().modelForce.y(), 0.0) << "z " << z;
        }
    }
}

/// A stiffness that followed the tip (no proxy): F = k(tip)·δ·ŷ, the work it does
/// round the same loop. What the god-object must not do.
double naiveWork(const std::vector<Vec3d>& loop)
{
    const SkinMap& map = *instance().skinMap();
    double w = 0.0;
    for (std::size_t i = 0; i + 1 < loop.size(); ++i) {
        const Vec3d m = map.toMap(loop[i]);
        const SkinSample s = map.sample(m.x(), m.y());
        const double depth = std::max(0.0, m.z() - s.skinMm);
        w += s.stiffnessNPerMm * depth * (loop[i + 1] - loop[i]).y();
    }
    return w;
}

// Round closed loops that start and end above the skin the model returns no more
// than the sampled spring's leak, whatever the bone beneath does (Palpation.h).
TEST(Palpation, ClosedLoopsCreateNoEnergy)
{
    const double depth = 4.0;
    const Vec3d up(0.0, 3.0, 0.0);
    // In over the interspace, across to the spinous process at depth, out: the loop a
    // stiffness-follows-the-tip spring turns into energy.
    std::vector<std::vector<Vec3d>> loops = {
        {kInterspace + up, kInterspace + depth * kDown, kSpinous + depth * kDown, kSpinous + up, kInterspace + up},
        {kSpinous + up, kSpinous + depth * kDown, kInterspace + depth * kDown, kInterspace + up, kSpinous + up},
    };
    for (std::size_t l = 0; l < loops.size(); ++l) {
        Hand hand(instance(), loops[l][0]);
        std::vector<Vec3d> path{loops[l][0]};
        for (std::size_t i = 1; i < loops[l].size(); ++i) {
            const Vec3d from = loops[l][i - 1], to = loops[l][i];
            const int n = int(std::ceil((to - from).norm() / 0.002));
            for (int k = 1; k <= n; ++k) path.push_back(from + (double(k) / n) * (to - from));
        }
        for (std::size_t i = 1; i < path.size(); ++i) hand.move(path[i]);
        SCOPED_TRACE("loop " + std::to_string(l));
        EXPECT_LE(hand.work(), hand.leak() + kRoundOffNmm);
        if (l == 0) {
            // The naive law creates ½·(k_process − k_interspace)·δ² ≈ 1.4 N·mm here,
            // dozens of times the leak bound: the check above could fail.
            EXPECT_GT(naiveWork(path), 20.0 * hand.leak());
        }
    }
    // Circles and a random walk in contact, over processes, interspaces and the
    // edges between them.
    Hand hand(instance(), kSpinous + up);
    std::mt19937 rng(3);
    std::normal_distribution<double> g(0.0, 1.0);
    Vec3d tip = kSpinous + up;
    hand.line(kSpinous + 3.0 * kDown, 0.002);
    for (int i = 0; i <= 20000; ++i) {
        const double phi = 2.0 * kPi * i / 5000.0;
        hand.move(Vec3d(6.0 * std::sin(phi), -3.0 - 1.5 * std::sin(3.0 * phi), 12.0 + 10.0 * std::cos(phi)));
    }
    tip = Vec3d(0.0, -3.0, 22.0);
    hand.line(tip, 0.002);
    for (int i = 0; i < 60000; ++i) {
        tip += 0.002 * Vec3d(g(rng), g(rng), g(rng));
        tip.y() = std::clamp(tip.y(), -8.0, 1.0);
        tip.z() = std::clamp(tip.z(), -25.0, 25.0);
        tip.x() = std::clamp(tip.x(), -10.0, 10.0);
        hand.move(tip);
    }
    hand.line(Vec3d(tip.x(), 3.0, tip.z()), 0.002);
    hand.line(kSpinous + up, 0.002);
    EXPECT_LE(hand.work(), hand.leak() + kRoundOffNmm);
    EXPECT_FALSE(hand.out().palpation.contact);
}

// Off by default: a scene with palpation inserts exactly as without it, since the
// tip starts on the path, out of contact, and the needle takes over at once.
TEST(Palpation, TheScriptedInsertionIsUnchanged)
{
    const SceneInstance plain(loadScene("senac-average"), nullptr, table());
    auto a = plain.makeModel();
    auto b = instance().makeModel();
    const InsertionScript script = InsertionScript::constantSpeed(-5.0, 20.0, 2.0);
    const InsertionResult ra = runInsertion(*a, script, 1000.0), rb = runInsertion(*b, script, 1000.0);
    ASSERT_EQ(ra.rows.size(), rb.rows.size());
    for (std::size_t i = 0; i < ra.rows.size(); ++i) {
        ASSERT_EQ(ra.rows[i].force, rb.rows[i].force) << "tick " << i;
        ASSERT_EQ(ra.rows[i].eventCount, rb.rows[i].eventCount) << "tick " << i;
    }
    EXPECT_EQ(ra.summary.pops, rb.summary.pops);
    EXPECT_GT(rb.summary.pops, 0);
}

// The built-in palpation scenes (issue 42 item 6) are their base scenes with the
// palpation block added, nothing else: the same insertion tick for tick. On their
// own phantom the back is felt before the needle: over the lower spinous process
// (bone 13 mm under the skin) k = E·A/T (3 N/13 mm), stiffer than over the
// interspace beside the entry (T from the analytic model), at a 2 mm press.
TEST(Palpation, BuiltinPalpationScenesFeelTheBackAndInsertAsTheirBaseScenes)
{
    for (const auto& [variant, base] : {std::pair<std::string, std::string>{"senac-average-palpation", "senac-average"},
             {"lumbar-puncture-palpation", "lumbar-puncture"}}) {
        SCOPED_TRACE(variant);
        std::ifstream vin(VOXHAP_SOURCE_DIR "/data/scenes/" + variant + ".json"),
            bin(VOXHAP_SOURCE_DIR "/data/scenes/" + base + ".json");
        Json v = Json::parse(vin), b = Json::parse(bin);
        EXPECT_NE(v.at("source").get<std::string>().find("[C-ui]"), std::string::npos);
        EXPECT_NE(v.at("source").get<std::string>().find("[chosen]"), std::string::npos);
        ASSERT_TRUE(v.at("terms").contains("palpation"));
        for (const char* key : {"name", "description", "source"}) v.erase(key), b.erase(key);
        v["terms"].erase("palpation");
        EXPECT_EQ(v, b) << "the variant differs from its base in more than the palpation block";

        const SceneInstance with(loadScene(variant), nullptr, table()), without(loadScene(base), nullptr, table());
        ASSERT_TRUE(with.skinMap());
        auto a = with.makeModel();
        auto c = without.makeModel();
        const InsertionScript script = InsertionScript::constantSpeed(-5.0, 25.0, 5.0);
        const InsertionResult ra = runInsertion(*a, script, 1000.0), rc = runInsertion(*c, script, 1000.0);
        ASSERT_EQ(ra.rows.size(), rc.rows.size());
        for (std::size_t i = 0; i < ra.rows.size(); ++i) ASSERT_EQ(ra.rows[i].force, rc.rows[i].force) << i;

        const double delta = 2.0, kEA = 30e-3 * 100.0; // 30 kPa over 100 mm² [N]
        Hand process(with, kSpinous + Vec3d(0.0, 5.0, 0.0)), interspace(with, kInterspace + Vec3d(4.0, 5.0, 0.0));
        process.line(kSpinous + delta * kDown, 0.01);
        interspace.line(kInterspace + Vec3d(4.0, 0.0, 0.0) + delta * kDown, 0.01);
        ASSERT_TRUE(process.out().palpating && interspace.out().palpating);
        const double tProcess = analyticBoneDepth(kSpinous.x(), kSpinous.z());
        const double tInter = analyticBoneDepth(4.0, kInterspace.z());
        EXPECT_NEAR(process.out().modelForce.y(), kEA / tProcess * delta, 1e-9);
        EXPECT_NEAR(
            interspace.out().modelForce.y(), kEA / tInter * delta, delta * kEA * kHalfVoxelMm / (tInter * tInter));
        EXPECT_GT(process.out().modelForce.y(), 3.0 * interspace.out().modelForce.y());
    }
}

// The hand-over happens only out of contact: sliding in contact onto the entry keeps
// palpating (the interspace is felt, not cut); lifting and coming down at the entry
// is the needle, which tents and punctures the skin.
TEST(Palpation, TheNeedleTakesOverOnlyAtTheEntryAndOutOfContact)
{
    const Vec3d entry = instance().entry();
    Hand hand(instance(), kSpinous + Vec3d(0.0, 3.0, 0.0));
    hand.line(kSpinous + 2.0 * kDown, 0.01);
    hand.line(entry + 2.0 * kDown, 0.01); // slide onto the entry in contact
    EXPECT_TRUE(hand.out().palpating);
    EXPECT_FALSE(hand.saw(EventType::SkinContact));
    hand.line(entry + Vec3d(0.0, 3.0, 0.0), 0.01); // lift: the needle's turn
    EXPECT_FALSE(hand.out().palpating);
    hand.line(entry + 15.0 * kDown, 0.002);
    EXPECT_TRUE(hand.saw(EventType::SkinContact));
    EXPECT_TRUE(hand.saw(EventType::SkinEntry));
    EXPECT_FALSE(hand.out().palpating);
    // Out again and away: palpation once more.
    hand.line(entry + Vec3d(0.0, 3.0, 0.0), 0.01);
    hand.line(kSpinous + Vec3d(0.0, 3.0, 0.0), 0.05);
    hand.line(kSpinous + 1.0 * kDown, 0.01);
    EXPECT_TRUE(hand.out().palpating);
    EXPECT_NEAR(hand.out().modelForce.y(), kEAN / 13.0 * 1.0, 1e-9);
}

// Without labels the skin and the bone come from HU (physics.md §5.2 thresholds).
TEST(Palpation, SkinMapFromHuAgreesWithTheLabels)
{
    volume::GridSpec grid;
    grid.spacing = Vec3d::Constant(kSpacingMm);
    const volume::PhantomModel m = volume::lumbarModel(volume::LumbarParams{}, table());
    volume::Volume v = volume::makePhantom(m, grid, table());
    v.removeGrid(volume::Channel::Label);
    PalpationParams p;
    p.radiusMm = 25.0;
    const SkinMap map(v, table(), Vec3d::Zero(), kDown, p, 0.5);
    EXPECT_FALSE(map.fromLabels());
    const Vec3d ms = map.toMap(kSpinous);
    const SkinSample s = map.sample(ms.x(), ms.y());
    ASSERT_TRUE(s.surface);
    // Trilinear HU crosses the threshold between the last air and the first skin
    // voxel centres: within a voxel of the face; the bone likewise.
    EXPECT_NEAR(s.skinMm, 0.0, kSpacingMm);
    EXPECT_NEAR(s.thicknessMm, 13.0, 2.0 * kSpacingMm);
    PalpationParams labelsOnly = p;
    labelsOnly.source = SkinSource::Labels;
    EXPECT_THROW(SkinMap(v, table(), Vec3d::Zero(), kDown, labelsOnly, 0.5), ValueError);
}

TEST(Palpation, SceneKeysAreReadAndRefusedNamingTheField)
{
    const Scene s = parseScene(palpationScene({{"friction_bone", 0.7}, {"source", "hu"}}).dump(), "p.json");
    EXPECT_TRUE(s.terms.palpation.on);
    EXPECT_DOUBLE_EQ(s.terms.palpation.params.frictionBone, 0.7);
    EXPECT_EQ(s.terms.palpation.params.source, SkinSource::Hu);
    const auto refusal = [](const Json& j) {
        try {
            (void)parseScene(j.dump(), "p.json");
        } catch (const ValueError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_NE(refusal(palpationScene({{"source", "sonar"}})).find("p.json: terms.palpation.source: must be"),
        std::string::npos);
    EXPECT_NE(refusal(palpationScene({{"stiffnes", 1.0}})).find("p.json: terms.palpation.stiffnes: unknown field"),
        std::string::npos);
    // Off by default: no block, no term.
    EXPECT_FALSE(loadScene("senac-average").terms.palpation.on);
}

} // namespace
} // namespace voxhap::haptic
