// SPDX-License-Identifier: Apache-2.0
/// @file TestShaftIntegration.cpp
/// @brief Shaft integrals against the closed forms of physics.md §7: R1
/// (layered slab, any angle, anisotropic voxels) and R5 (sphere in slab).

#include "common/Phantom.h"
#include "common/Tolerances.h"

#include "core/Errors.h"
#include "haptic/shaft/LabelTrace.h"
#include "haptic/shaft/ShaftIntegration.h"
#include "haptic/shaft/TrajectoryProfile.h"
#include "haptic/shaft/detail/VoxelWalk.h"

#include <Eigen/Geometry>

#include <cmath>
#include <numeric>
#include <random>

namespace voxhap::haptic {
namespace {

using test::kChordSumRelative;
using test::kExactRelative;
using test::testBeta;

/// R1 layers, each a multiple of 0.4 and 0.5 mm so that they sit on voxel faces.
const std::vector<volume::SlabLayer> kR1Layers{
    {"skin", 2.0}, {"fat", 8.0}, {"muscle", 10.0}, {"interspinous_ligament", 6.0}, {"fat", 4.0}};

/// β of a layer as the grid stores it (float): the closed form uses the field's own values.
double storedBeta(const std::string& tissue) { return double(float(testBeta().at(tissue))); }

/// physics.md §7 R1: ∫β ds to arc length s at angle θ from the normal,
/// Σ_j β_j · clip(s·cosθ − z_j, 0, t_j)/cosθ.
double r1Exact(double s, double cosTheta)
{
    double z = 0.0, sum = 0.0;
    for (const auto& l : kR1Layers) {
        sum += storedBeta(l.tissue) * std::clamp(s * cosTheta - z, 0.0, l.thicknessMm) / cosTheta;
        z += l.thicknessMm;
    }
    return sum;
}

/// Σ|Δβ| over the boundaries met by depth s·cosθ (the entry surface included), and max|Δβ|.
std::pair<double, double> r1Jumps(double depth)
{
    double prev = 0.0, z = 0.0, sum = 0.0, max = 0.0;
    for (const auto& l : kR1Layers) {
        if (depth + 1e-12 < z) break;
        const double jump = std::abs(storedBeta(l.tissue) - prev);
        sum += jump;
        max = std::max(max, jump);
        prev = storedBeta(l.tissue);
        z += l.thicknessMm;
    }
    if (depth + 1e-12 >= z) { // the bottom: tissue -> air
        sum += prev;
        max = std::max(max, prev);
    }
    return {sum, max};
}

struct Direction {
    double thetaDeg;
    Vec3d u;
};

Direction direction(double thetaDeg)
{
    const double t = degToRad(thetaDeg), phi = degToRad(37.0); // azimuth off the grid axes
    return {thetaDeg, Vec3d(std::sin(t) * std::cos(phi), -std::cos(t), std::sin(t) * std::sin(phi))};
}

/// physics.md §7 R1: the layered slab.
class ShaftOnLayeredSlab : public testing::TestWithParam<Vec3d> {
protected:
    static std::map<std::tuple<double, double, double>, test::FieldFixture>& cache()
    {
        static std::map<std::tuple<double, double, double>, test::FieldFixture> c;
        return c;
    }
    const test::FieldFixture& fixture() const
    {
        const Vec3d h = GetParam();
        auto& c = cache();
        const auto key = std::make_tuple(h.x(), h.y(), h.z());
        if (!c.count(key)) {
            volume::SlabParams p;
            p.layers = kR1Layers;
            p.halfWidthMm = 60.0; // a 60° shaft through 30 mm drifts 52 mm sideways
            p.grid.spacing = h;
            c.emplace(key, test::makeFieldFixture(volume::slabModel(p, volume::TissueTable::builtin()), p.grid));
        }
        return c.at(key);
    }
    const Vec3d kEntry{0.123, 0.0, -0.377};
    static constexpr double kTotal = 30.0;
};

TEST_P(ShaftOnLayeredSlab, ExactVoxelMatchesClosedFormAtEveryAngle)
{
    auto exact = makeIntegrator(*fixture().field, {Strategy::ExactVoxel});
    ShaftIntegral out;
    for (double theta : {0.0, 30.0, 60.0}) {
        const Direction d = direction(theta);
        const double cosT = std::cos(degToRad(theta)), sMax = 1.1 * kTotal / cosT;
        for (int i = 0; i <= 97; ++i) {
            const double s = sMax * i / 97.0;
            exact->integrate({kEntry, kEntry + s * d.u}, out);
            const double expected = r1Exact(s, cosT);
            ASSERT_NEAR(out.dampingIntegral, expected, kExactRelative * expected + 1e-15)
                << "theta " << theta << " s " << s;
            // Chords sum to the shaft length, split by label as the layers dictate.
            const double sum = std::accumulate(out.labelLengthMm.begin(), out.labelLengthMm.end(), 0.0);
            ASSERT_NEAR(sum, s, kChordSumRelative * s);
        }
    }
}

TEST_P(ShaftOnLayeredSlab, LabelLengthsAndFirstHitsFollowTheLayers)
{
    auto exact = makeIntegrator(*fixture().field, {Strategy::ExactVoxel});
    const auto& table = volume::TissueTable::builtin();
    ShaftIntegral out;
    const Direction d = direction(30.0);
    const double cosT = std::cos(degToRad(30.0)), s = 25.0 / cosT; // tip at depth 25: in the ligament
    exact->integrate({kEntry, kEntry + s * d.u}, out);
    ASSERT_TRUE(out.labelsValid);
    const auto len = [&](const char* n) { return out.labelLengthMm[std::size_t(table.at(n).id)]; };
    const auto hit = [&](const char* n) { return out.firstHitMm[std::size_t(table.at(n).id)]; };
    EXPECT_NEAR(len("skin"), 2.0 / cosT, 1e-9);
    EXPECT_NEAR(len("fat"), 8.0 / cosT, 1e-9); // the deeper fat layer is not reached
    EXPECT_NEAR(len("muscle"), 10.0 / cosT, 1e-9);
    EXPECT_NEAR(len("interspinous_ligament"), 5.0 / cosT, 1e-9);
    EXPECT_NEAR(hit("skin"), 0.0, 1e-12);
    EXPECT_NEAR(hit("muscle"), 10.0 / cosT, 1e-9);
    EXPECT_NEAR(hit("interspinous_ligament"), 20.0 / cosT, 1e-9);
    EXPECT_EQ(hit("lung"), kNotHit);
}

TEST_P(ShaftOnLayeredSlab, TrilinearMarchWithinThePhysicsBound)
{
    // physics.md §7 R1: |ΔF| <= v0·[max|Δβ|·h/(8cosθ) + Σ|Δβ|·cosθ·Δs²/(4h)], h the voxel size
    // along the normal. The first term (smearing) assumes both sides of every boundary lie on
    // the shaft. A shaft that starts on the skin surface sees only the inner half of the
    // surface's smear, a deficit of β_skin·h/(8cosθ) that stays once the tip is past it: the
    // printed bound omits it. So: shafts that start half a voxel up in the air meet the printed
    // bound; shafts that start on the surface meet it plus that entry term.
    const double h = GetParam().y();
    const double entryTerm = storedBeta("skin") * h / 8.0;
    for (double fraction : {1.0, 0.5, 0.25, 0.125}) {
        IntegratorOptions o{Strategy::MarchTrilinear};
        o.stepMm = fraction * h;
        auto march = makeIntegrator(*fixture().field, o);
        ShaftIntegral out;
        for (double theta : {0.0, 30.0, 60.0}) {
            const Direction d = direction(theta);
            const double cosT = std::cos(degToRad(theta)), sMax = 1.05 * kTotal / cosT;
            const double above = 0.5 * h / cosT; // arc length of the shaft in the air
            for (int i = 1; i <= 61; ++i) {
                const double s = sMax * i / 61.0;
                const auto [sumJump, maxJump] = r1Jumps(s * cosT + 0.5 * h);
                const double printed = maxJump * h / (8.0 * cosT) + sumJump * cosT * o.stepMm * o.stepMm / (4.0 * h);
                march->integrate({kEntry - above * d.u, kEntry + s * d.u}, out);
                ASSERT_LE(std::abs(out.dampingIntegral - r1Exact(s, cosT)), printed + 1e-15)
                    << "from the air: step " << o.stepMm << " theta " << theta << " s " << s;
                march->integrate({kEntry, kEntry + s * d.u}, out);
                ASSERT_LE(std::abs(out.dampingIntegral - r1Exact(s, cosT)), printed + entryTerm / cosT + 1e-15)
                    << "from the surface: step " << o.stepMm << " theta " << theta << " s " << s;
            }
        }
    }
}

TEST_P(ShaftOnLayeredSlab, NearestMarchWithinHalfAStepPerBoundary)
{
    const double h = GetParam().y();
    IntegratorOptions o{Strategy::MarchNearest};
    o.stepMm = 0.25 * h;
    auto march = makeIntegrator(*fixture().field, o);
    ShaftIntegral out;
    for (double theta : {0.0, 30.0, 60.0}) {
        const Direction d = direction(theta);
        const double cosT = std::cos(degToRad(theta));
        for (int i = 1; i <= 61; ++i) {
            const double s = 1.05 * kTotal / cosT * i / 61.0;
            march->integrate({kEntry, kEntry + s * d.u}, out);
            // The voxels reproduce the layers exactly (faces), so the only error is the
            // trapezoid rule on each jump: at most |Δβ|·Δs/2 per boundary crossed.
            const double bound = r1Jumps(s * cosT).first * o.stepMm / 2.0;
            ASSERT_LE(std::abs(out.dampingIntegral - r1Exact(s, cosT)), bound + 1e-15) << theta << " " << s;
        }
    }
}

TEST_P(ShaftOnLayeredSlab, ExactTrilinearIsTheLimitOfTheTrilinearMarch)
{
    const double h = GetParam().y();
    auto exactTri = makeIntegrator(*fixture().field, {Strategy::ExactTrilinear});
    IntegratorOptions fine{Strategy::MarchTrilinear};
    fine.stepMm = h / 64.0;
    auto march = makeIntegrator(*fixture().field, fine);
    ShaftIntegral a, b;
    for (double theta : {0.0, 30.0, 60.0}) {
        const Direction d = direction(theta);
        const double cosT = std::cos(degToRad(theta)), above = 0.5 * h / cosT;
        for (int i = 1; i <= 23; ++i) {
            const double s = 1.05 * kTotal / cosT * i / 23.0;
            const Segment seg{kEntry - above * d.u, kEntry + s * d.u}; // from the air, as in the march test
            exactTri->integrate(seg, a);
            march->integrate(seg, b);
            const auto [sumJump, maxJump] = r1Jumps(s * cosT + 0.5 * h);
            // Against the fine march: only its trapezoid term remains (§7 R1, second term).
            EXPECT_LE(std::abs(a.dampingIntegral - b.dampingIntegral),
                sumJump * cosT * fine.stepMm * fine.stepMm / (4.0 * h) + 1e-14);
            // Against the piecewise-constant closed form: only the smearing term (Δs -> 0), which
            // this exact integral attains with the tip on a boundary (1e-9 relative for round-off).
            EXPECT_LE(std::abs(a.dampingIntegral - r1Exact(s, cosT)), maxJump * h / (8.0 * cosT) * (1.0 + 1e-9));
        }
    }
}

TEST_P(ShaftOnLayeredSlab, ProfileOnTheLockedLineIsExact)
{
    TrajectoryProfile profile(*fixture().field, 0.05, 200.0, true);
    ShaftIntegral out;
    for (double theta : {0.0, 30.0, 60.0}) {
        const Direction d = direction(theta);
        const double cosT = std::cos(degToRad(theta)), sMax = 1.1 * kTotal / cosT;
        ASSERT_TRUE(profile.lock(kEntry, d.u));
        const auto rebuilds = profile.rebuilds();
        for (int i = 0; i <= 211; ++i) {
            const double s = sMax * i / 211.0;
            profile.integrate({kEntry, kEntry + s * d.u}, out);
            const double expected = r1Exact(s, cosT);
            ASSERT_NEAR(out.dampingIntegral, expected, kExactRelative * expected + 1e-15) << theta << " " << s;
        }
        EXPECT_EQ(profile.rebuilds(), rebuilds) << "queries on the line must not rebuild";
    }
}

/// A bent shaft (physics.md §9.5): an arc of radius @p radius from the entry, bending
/// sideways as it goes down, cut into @p pieces chords; depth grows along every chord.
std::vector<Vec3d> arcPolyline(const Vec3d& entry, double length, double radius, int pieces)
{
    const Vec3d down(0, -1, 0), side = Vec3d(0.8, 0, 0.6);
    std::vector<Vec3d> p;
    for (int i = 0; i <= pieces; ++i) {
        const double a = length * i / pieces / radius;
        p.push_back(entry + radius * (std::sin(a) * down + (1.0 - std::cos(a)) * side));
    }
    return p;
}

/// R1 along a chord from depth za to zb (zb > za), length len: Σ_j β_j·overlap_j·len/(zb − za).
double r1Chord(double za, double zb, double len)
{
    double z = 0.0, sum = 0.0;
    for (const auto& l : kR1Layers) {
        sum += storedBeta(l.tissue) * std::max(0.0, std::min(zb, z + l.thicknessMm) - std::max(za, z));
        z += l.thicknessMm;
    }
    return sum * len / (zb - za);
}

TEST_P(ShaftOnLayeredSlab, BentShaftMatchesTheClosedFormChordByChord)
{
    auto exact = makeIntegrator(*fixture().field, {Strategy::ExactVoxel});
    const auto& table = volume::TissueTable::builtin();
    const std::vector<Vec3d> shaft = arcPolyline(kEntry, 28.0, 60.0, 37);
    ShaftIntegral out;
    exact->integratePolyline(shaft, out);
    double expected = 0.0, length = 0.0, muscleHit = kNotHit;
    for (std::size_t i = 1; i < shaft.size(); ++i) {
        const double za = kEntry.y() - shaft[i - 1].y(), zb = kEntry.y() - shaft[i].y();
        const double len = (shaft[i] - shaft[i - 1]).norm();
        expected += r1Chord(za, zb, len);
        if (muscleHit == kNotHit && zb > 10.0) muscleHit = length + len * (10.0 - za) / (zb - za); // skin 2 + fat 8
        length += len;
    }
    EXPECT_NEAR(out.dampingIntegral, expected, kExactRelative * expected);
    EXPECT_NEAR(out.lengthMm, length, kChordSumRelative * length);
    const double sum = std::accumulate(out.labelLengthMm.begin(), out.labelLengthMm.end(), 0.0);
    EXPECT_NEAR(sum, length, kChordSumRelative * length);
    EXPECT_NEAR(out.firstHitMm[std::size_t(table.at("muscle").id)], muscleHit, 1e-9);
    // Control: the chord from entry to tip, the straight needle, integrates less tissue.
    ShaftIntegral chord;
    exact->integrate({shaft.front(), shaft.back()}, chord);
    EXPECT_GT(std::abs(chord.dampingIntegral - expected), 100.0 * kExactRelative * expected);
}

TEST_P(ShaftOnLayeredSlab, EveryStrategyIntegratesAPolylineAsTheSumOfItsChords)
{
    const std::vector<Vec3d> shaft = arcPolyline(kEntry, 28.0, 40.0, 23);
    TrajectoryProfile profile(*fixture().field, 0.05, 200.0, true);
    ShaftIntegral exactBent;
    makeIntegrator(*fixture().field, {Strategy::ExactVoxel})->integratePolyline(shaft, exactBent);
    for (const Strategy st : {Strategy::ExactVoxel, Strategy::ExactTrilinear, Strategy::MarchNearest,
             Strategy::MarchTrilinear, Strategy::Profile}) {
        IntegratorOptions o;
        o.strategy = st;
        auto integ = makeIntegrator(*fixture().field, o);
        ShaftIntegral bent, piece;
        integ->integratePolyline(shaft, bent);
        // The reference: each chord integrated on its own (the straight shaft, checked
        // against R1 above), lengths summed, first hits offset by the length before.
        double damping = 0.0, offset = 0.0;
        std::array<double, kMaxLabels> lengths{}, hits;
        hits.fill(kNotHit);
        for (std::size_t i = 1; i < shaft.size(); ++i) {
            auto single = makeIntegrator(*fixture().field, o); // a fresh profile locks on each chord
            single->integrate({shaft[i - 1], shaft[i]}, piece);
            damping += piece.dampingIntegral;
            for (std::size_t l = 0; l < kMaxLabels; ++l) {
                lengths[l] += piece.labelLengthMm[l];
                if (hits[l] == kNotHit && piece.firstHitMm[l] != kNotHit) hits[l] = offset + piece.firstHitMm[l];
            }
            offset += piece.lengthMm;
        }
        EXPECT_NEAR(bent.dampingIntegral, damping, 1e-12 * damping) << integ->name();
        EXPECT_NEAR(bent.lengthMm, offset, 1e-12 * offset) << integ->name();
        for (std::size_t l = 0; l < kMaxLabels; ++l) {
            EXPECT_NEAR(bent.labelLengthMm[l], lengths[l], 1e-12 * offset) << integ->name() << " label " << l;
            if (hits[l] == kNotHit)
                EXPECT_EQ(bent.firstHitMm[l], kNotHit) << integ->name() << " label " << l;
            else
                EXPECT_NEAR(bent.firstHitMm[l], hits[l], 1e-12 * offset) << integ->name() << " label " << l;
        }
        // The profile answers a bent shaft exactly as the exact traversal does (§9.5).
        if (st == Strategy::Profile) {
            EXPECT_EQ(bent.dampingIntegral, exactBent.dampingIntegral);
        }
    }
}

TEST_P(ShaftOnLayeredSlab, BentShaftsOfOnePointOrANonFinitePointIntegrateToZero)
{
    std::vector<Vec3d> shaft = arcPolyline(kEntry, 20.0, 40.0, 9);
    for (const Strategy st :
        {Strategy::ExactVoxel, Strategy::ExactTrilinear, Strategy::MarchTrilinear, Strategy::Profile}) {
        IntegratorOptions o;
        o.strategy = st;
        auto integ = makeIntegrator(*fixture().field, o);
        ShaftIntegral out;
        integ->integratePolyline(shaft, out);
        EXPECT_GT(out.dampingIntegral, 0.0) << "control: the shaft is in tissue";
        integ->integratePolyline(std::span<const Vec3d>(shaft.data(), 1), out);
        EXPECT_EQ(out.dampingIntegral, 0.0);
        EXPECT_EQ(out.lengthMm, 0.0);
        std::vector<Vec3d> bad = shaft;
        bad[4].x() = std::nan("");
        integ->integratePolyline(bad, out);
        EXPECT_EQ(out.dampingIntegral, 0.0);
        EXPECT_EQ(out.lengthMm, 0.0);
    }
}

TEST_P(ShaftOnLayeredSlab, LabelRunsAlongABentPathFollowTheLayers)
{
    const auto& table = volume::TissueTable::builtin();
    const LabelTracer tracer(*fixture().field);
    // From 3 mm above the skin, so that leading air is dropped.
    const std::vector<Vec3d> shaft = arcPolyline(kEntry + Vec3d(0, 3, 0), 30.0, 50.0, 31);
    const std::vector<LabelRun> runs = tracer.tracePolyline(shaft);
    // Where the path reaches each depth, walking its chords (the reference).
    const auto arcAtDepth = [&](double depth) {
        double s = 0.0;
        for (std::size_t i = 1; i < shaft.size(); ++i) {
            const double za = -shaft[i - 1].y(), zb = -shaft[i].y(), len = (shaft[i] - shaft[i - 1]).norm();
            if (zb >= depth) return s + len * (depth - za) / (zb - za);
            s += len;
        }
        return kNotHit;
    };
    ASSERT_GE(runs.size(), 4u);
    const char* names[] = {"skin", "fat", "muscle", "interspinous_ligament"};
    const double tops[] = {0.0, 2.0, 10.0, 20.0};
    for (int i = 0; i < 4; ++i) {
        EXPECT_EQ(runs[std::size_t(i)].label, table.at(names[i]).id) << i;
        EXPECT_NEAR(runs[std::size_t(i)].startMm, arcAtDepth(tops[i]), 1e-9) << names[i];
    }
    // Control: the straight trace from the same start along the first chord meets
    // the muscle elsewhere.
    const std::vector<LabelRun> straight = tracer.trace(shaft.front(), shaft[1] - shaft[0], 30.0);
    ASSERT_GE(straight.size(), 3u);
    EXPECT_GT(std::abs(straight[2].startMm - runs[2].startMm), 1e-3);
    EXPECT_THROW(tracer.tracePolyline(std::span<const Vec3d>(shaft.data(), 1)), ValueError);
}

INSTANTIATE_TEST_SUITE_P(Spacings, ShaftOnLayeredSlab, testing::Values(Vec3d(0.5, 0.5, 0.5), Vec3d(0.6, 0.4, 0.9)),
    [](const auto& param) { return param.index == 0 ? "Isotropic" : "Anisotropic"; });

/// physics.md §7 R5: sphere of radius R (β_s) in a slab (β0), isotropic and anisotropic voxels.
/// physics.md §7 R5: the sphere in a slab.
class ShaftThroughSphere : public testing::TestWithParam<Vec3d> {
protected:
    const test::FieldFixture& fixture() const
    {
        static std::map<std::tuple<double, double, double>, test::FieldFixture> cache;
        const Vec3d h = GetParam();
        const auto key = std::make_tuple(h.x(), h.y(), h.z());
        if (!cache.count(key)) {
            volume::SphereParams p; // 40 mm of fat, muscle sphere r = 10 mm centred at depth 20
            p.halfWidthMm = 75.0;
            p.grid.spacing = h;
            cache.emplace(key, test::makeFieldFixture(volume::sphereModel(p, volume::TissueTable::builtin()), p.grid));
        }
        return cache.at(key);
    }
    /// The largest voxel side: the voxelisation bound of §7 R5 is stated for cubes of side h.
    double h() const { return GetParam().maxCoeff(); }
    static constexpr double kR = 10.0, kT = 40.0;
    static inline const Vec3d kCentre{0.0, -20.0, 0.0};
};

TEST_P(ShaftThroughSphere, ExactVoxelWithinTheVoxelisationBound)
{
    const double b0 = testBeta().at("fat"), bs = testBeta().at("muscle");
    auto exact = makeIntegrator(*fixture().field, {Strategy::ExactVoxel});
    ShaftIntegral out;
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (double theta : {0.0, 30.0, 60.0}) {
        for (int n = 0; n < 40; ++n) {
            // A line at angle theta whose closest approach to the centre is rho <= 0.8 R.
            const Direction d = direction(theta);
            Vec3d side = d.u.cross(Vec3d::UnitX()).normalized();
            side = Eigen::AngleAxisd(2.0 * kPi * unit(rng), d.u) * side;
            const double rho = 0.8 * kR * unit(rng);
            const Vec3d closest = kCentre + rho * side;
            // From the top surface (y = 0) to the bottom (y = -T) along u.
            const double toTop = (0.0 - closest.y()) / d.u.y(), toBottom = (-kT - closest.y()) / d.u.y();
            const Segment seg{closest + toTop * d.u, closest + toBottom * d.u};
            exact->integrate(seg, out);
            const double length = (seg.tip - seg.entry).norm();
            const double expected = b0 * length + (bs - b0) * 2.0 * std::sqrt(kR * kR - rho * rho);
            // A centre-sampled voxel sphere differs from the true chord by at most 1.79h
            // for rho <= 0.8R (physics.md §7 R5): allow 2h·|Δβ|.
            ASSERT_LE(std::abs(out.dampingIntegral - expected), 2.0 * h() * (bs - b0)) << theta << " " << rho;
        }
    }
}

TEST_P(ShaftThroughSphere, ExactVoxelEqualsSupersampledVoxelField)
{
    // Against a march over the same voxels with steps of 2e-5 h: its trapezoid error is
    // at most |Δβ|·Δs/2 per voxel face crossed (< 100 faces here), far below the 1e-3·h·|Δβ|
    // tolerance of physics.md §7 R5.
    const double dBeta = testBeta().at("muscle") - testBeta().at("fat");
    auto exact = makeIntegrator(*fixture().field, {Strategy::ExactVoxel});
    IntegratorOptions fine{Strategy::MarchNearest};
    fine.stepMm = 2e-5 * h();
    fine.trackLabels = false;
    auto march = makeIntegrator(*fixture().field, fine);
    ShaftIntegral a, b;
    for (double theta : {0.0, 30.0, 60.0}) {
        const Direction d = direction(theta);
        const Vec3d closest = kCentre + Vec3d(3.1, 0.0, -2.3);
        const double toTop = (0.0 - closest.y()) / d.u.y(), toBottom = (-kT - closest.y()) / d.u.y();
        const Segment seg{closest + toTop * d.u, closest + toBottom * d.u};
        exact->integrate(seg, a);
        march->integrate(seg, b);
        EXPECT_LE(std::abs(a.dampingIntegral - b.dampingIntegral), 1e-3 * h() * dBeta) << theta;
    }
}

INSTANTIATE_TEST_SUITE_P(Spacings, ShaftThroughSphere, testing::Values(Vec3d(0.5, 0.5, 0.5), Vec3d(0.6, 0.4, 0.5)),
    [](const auto& param) { return param.index == 0 ? "Isotropic" : "Anisotropic"; });

} // namespace
} // namespace voxhap::haptic

namespace voxhap::haptic {
namespace {

/// A grid that mixes every kind of block the exact walk meets: leaves of
/// random values (some voxels inactive, some NaN if @p withNaN), 8³ tiles
/// (runs of them), a 128³ tile and background, on anisotropic voxels; leaves
/// and tiles on both sides of index 0 (the walk's leaf and node arithmetic on
/// negative coordinates) and across the boundaries of 128³ nodes.
volume::FloatGrid::Ptr mixedBlockGrid(std::mt19937& rng, bool withNaN)
{
    auto g = volume::FloatGrid::create(0.0f);
    openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();
    m.preScale(openvdb::Vec3d(0.7, 0.9, 1.25));
    m.postTranslate(openvdb::Vec3d(-3.0, 5.0, 11.0));
    g->setTransform(openvdb::math::Transform::createLinearTransform(m));
    std::uniform_real_distribution<float> value(0.001f, 0.02f);
    std::uniform_int_distribution<int> kind(0, 9);
    auto acc = g->getAccessor();
    for (int bx = -64; bx < 128; bx += 8) {
        for (int by = 0; by < 128; by += 8) {
            for (int bz = 0; bz < 128; bz += 8) {
                const int k = kind(rng);
                if (k < 4) { // a leaf
                    for (int i = 0; i < 512; ++i) {
                        const openvdb::Coord c(bx + (i >> 6), by + ((i >> 3) & 7), bz + (i & 7));
                        const int v = kind(rng);
                        if (v == 0) continue; // inactive background inside a leaf
                        acc.setValue(c, withNaN && v == 1 && i % 97 == 0 ? std::nanf("") : value(rng));
                    }
                } else if (k < 8) { // an 8³ tile (long runs: six in ten blocks)
                    g->tree().addTile(1, openvdb::Coord(bx, by, bz), value(rng), true);
                } // else background
            }
        }
    }
    g->tree().addTile(2, openvdb::Coord(128, 0, 0), 0.013f, true); // one 128³ tile beside them
    return g;
}

/// The exact chord sum found without any walk: every crossing of a voxel face
/// plane (index planes k + 1/2) along the segment, sorted; each interval takes
/// the value of the voxel at its midpoint (NaN counts nothing).
double planeCrossingSum(const volume::FloatGrid& g, const Segment& s)
{
    const openvdb::Vec3d a = g.transform().worldToIndex(volume::toVdb(s.entry));
    const openvdb::Vec3d b = g.transform().worldToIndex(volume::toVdb(s.tip));
    std::vector<double> ts{0.0, 1.0};
    for (int i = 0; i < 3; ++i) {
        if (a[i] == b[i]) continue;
        const double lo = std::min(a[i], b[i]), hi = std::max(a[i], b[i]);
        for (double k = std::ceil(lo - 0.5) + 0.5; k < hi; k += 1.0) ts.push_back((k - a[i]) / (b[i] - a[i]));
    }
    std::sort(ts.begin(), ts.end());
    auto acc = g.getConstAccessor();
    double sum = 0.0;
    for (std::size_t j = 0; j + 1 < ts.size(); ++j) {
        const double mid = 0.5 * (ts[j] + ts[j + 1]);
        const float v = acc.getValue(openvdb::Coord::round(a + (b - a) * mid));
        if (std::isfinite(v)) sum += double(v) * (ts[j + 1] - ts[j]);
    }
    return sum * (s.tip - s.entry).norm();
}

/// The walk's three regimes (voxel steps in leaves, block steps over runs of
/// 8³ tiles, one jump over a 128³ tile) and its switches between them, on
/// random shafts, shafts along an index axis and shafts in an index plane;
/// through the integrator and through the damping walk with either of its
/// lane types (detail::walk::ScalarPair, and the SSE2 pair where there is
/// one), on a grid with NaN voxels and on one without (the walk skips its
/// finiteness test there).
TEST(ExactVoxelWalk, EqualsThePlaneCrossingSumOnLeavesTilesAndBackground)
{
    for (const bool withNaN : {true, false}) {
        std::mt19937 rng(20261125);
        const auto grid = mixedBlockGrid(rng, withNaN);
        const MaterialField field(grid, nullptr, volume::TissueTable::builtin());
        const auto exact = makeIntegrator(field, {Strategy::ExactVoxel, 0.1, false});
        detail::WalkCursor<volume::FloatGrid::TreeType> cursor(grid->tree());
        ASSERT_EQ(cursor.allFinite, !withNaN);
        const detail::AffineIndexMap indexMap(grid->transform());
        openvdb::Vec3d lo, hi;
        detail::activeBox(*grid, 0.0, lo, hi);
        std::uniform_real_distribution<double> pos(-20.0, 200.0), posX(-90.0, 200.0);
        std::normal_distribution<double> gauss(0.0, 1.0);
        const openvdb::math::Transform& xf = grid->transform();
        const auto world = [&](double i, double j, double k) {
            return volume::fromVdb(xf.indexToWorld(openvdb::Vec3d(i, j, k)));
        };
        int checked = 0, negative = 0;
        for (int n = 0; n < 600; ++n) {
            Segment s;
            s.entry = world(posX(rng), pos(rng) * 0.6, pos(rng) * 0.6);
            Vec3d d(gauss(rng), gauss(rng), gauss(rng));
            if (n % 3 == 1) d = Vec3d::Unit(n % 9 / 3) * (n % 2 ? 1.0 : -1.0); // along an index axis
            if (n % 3 == 2) d[n % 9 / 3] = 0.0;                                // in an index plane
            s.tip = s.entry + 150.0 * d.normalized();
            ShaftIntegral out;
            exact->integrate(s, out);
            const double expected = planeCrossingSum(*grid, s);
            // Both sum the same chords; they differ by round-off in the crossing times
            // (kExactRelative), and a zero expected sum must come out zero.
            const double tolerance = test::kExactRelative * std::max(expected, 1e-12);
            EXPECT_NEAR(out.dampingIntegral, expected, tolerance) << "shaft " << n;
            const detail::IndexSegment is = detail::toIndex(indexMap, s, 0.5);
            const double scalar = detail::sumVoxels<decltype(cursor), detail::walk::ScalarPair>(is, lo, hi, cursor);
            EXPECT_NEAR(scalar * is.lengthMm, expected, tolerance) << "shaft " << n << ", scalar lanes";
            EXPECT_NEAR(detail::sumVoxels(is, lo, hi, cursor) * is.lengthMm, expected, tolerance) << "shaft " << n;
            checked += expected > 0.0;
            negative += expected > 0.0 && std::min(is.a[0], is.a[0] + is.d[0]) < 0.0;
        }
        EXPECT_GT(checked, 300); // most shafts cross something: the comparison is not vacuous
        EXPECT_GT(negative, 50); // and many reach the blocks at negative x
    }
}

} // namespace
} // namespace voxhap::haptic
