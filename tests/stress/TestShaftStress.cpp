// SPDX-License-Identifier: Apache-2.0
/// @file TestShaftStress.cpp
/// @brief Numerical stability of shaft integration (physics.md §6.4): faces,
/// edges and corners, zero-length and far-away shafts, huge volumes, NaN voxels
/// and inputs, random fuzz; and the servo-path rule that integration never allocates.

#include "common/Phantom.h"
#include "common/Tolerances.h"
#include "stress/AllocationCounter.h"

#include "haptic/shaft/ShaftIntegration.h"
#include "haptic/shaft/TrajectoryProfile.h"

#include <Eigen/Geometry> // for unitOrthogonal

#include <atomic>
#include <cstdlib>
#include <new>
#include <numeric>
#include <random>

namespace voxhap::haptic {
namespace {

using test::kChordSumRelative;

const std::vector<Strategy> kAll{Strategy::ExactVoxel, Strategy::ExactTrilinear, Strategy::MarchNearest,
    Strategy::MarchTrilinear, Strategy::Profile};

class Stress : public testing::Test {
protected:
    static void SetUpTestSuite()
    {
        volume::SlabParams p; // R1-style layers on voxel faces
        p.layers = {{"skin", 2.0}, {"fat", 8.0}, {"muscle", 10.0}};
        p.halfWidthMm = 30.0;
        p.grid.spacing = Vec3d::Constant(kH);
        slab = std::make_unique<test::FieldFixture>(
            test::makeFieldFixture(volume::slabModel(p, volume::TissueTable::builtin()), p.grid));
    }
    static void TearDownTestSuite() { slab.reset(); }
    static std::unique_ptr<ShaftIntegrator> make(Strategy s)
    {
        IntegratorOptions o{s};
        o.stepMm = 0.25 * kH;
        return makeIntegrator(*slab->field, o);
    }
    static double labelSum(const ShaftIntegral& r)
    {
        return std::accumulate(r.labelLengthMm.begin(), r.labelLengthMm.end(), 0.0);
    }
    static inline std::unique_ptr<test::FieldFixture> slab;
    static constexpr double kH = 0.5;
};

TEST_F(Stress, ShaftsAlongFacesAndEdgesAreDeterministicAndComplete)
{
    auto exact = make(Strategy::ExactVoxel);
    ShaftIntegral a, b, c;
    // Faces are at multiples of h. A vertical shaft on the face x = 0, on the edge x = z = 0,
    // and a horizontal one along y = -5 (inside fat) on the face z = 1.
    const std::vector<Segment> shafts{
        {{0.0, 1.0, 0.3}, {0.0, -19.0, 0.3}}, {{0.0, 1.0, 0.0}, {0.0, -19.0, 0.0}},
        {{-20.0, -5.0, 1.0}, {20.0, -5.0, 1.0}},
        {{-20.0, -5.5, 1.0}, {20.0, -5.5, 1.0}}, // a face between two fat voxels in y as well
    };
    for (const Segment& s : shafts) {
        exact->integrate(s, a);
        const double length = (s.tip - s.entry).norm();
        EXPECT_NEAR(labelSum(a), length, kChordSumRelative * length);
        // ±1e-9·h sideways: the neighbours across the face hold the same layer, so nothing changes.
        const Vec3d side = (s.tip - s.entry).unitOrthogonal() * 1e-9 * kH;
        exact->integrate({s.entry + side, s.tip + side}, b);
        exact->integrate({s.entry - side, s.tip - side}, c);
        EXPECT_NEAR(b.dampingIntegral, a.dampingIntegral, 1e-12 * a.dampingIntegral);
        EXPECT_NEAR(c.dampingIntegral, a.dampingIntegral, 1e-12 * a.dampingIntegral);
        // Deterministic: the same input gives bit-identical output.
        exact->integrate(s, b);
        EXPECT_EQ(a.dampingIntegral, b.dampingIntegral);
    }
}

TEST_F(Stress, ExactCornersSkipAndDoubleNothing)
{
    // Through lattice corners: direction (1,-1,1) from the corner (0,0,0) passes a corner every
    // h·sqrt(3). The layers depend on depth only, so the R1 closed form still holds (cosθ = 1/sqrt 3).
    auto exact = make(Strategy::ExactVoxel);
    ShaftIntegral r;
    const Vec3d u = Vec3d(1, -1, 1).normalized();
    const double cosT = 1.0 / std::sqrt(3.0);
    for (double s : {5.0, 17.3205080756887729, 34.0}) {
        exact->integrate({Vec3d::Zero(), s * u}, r);
        const double depth = s * cosT;
        const double expected = (double(float(8152e-6)) * std::clamp(depth, 0.0, 2.0) +
                                    double(float(3696e-6)) * std::clamp(depth - 2.0, 0.0, 8.0) +
                                    double(float(8152e-6)) * std::clamp(depth - 10.0, 0.0, 10.0)) /
            cosT;
        EXPECT_NEAR(r.dampingIntegral, expected, test::kExactRelative * expected);
        EXPECT_NEAR(labelSum(r), s, kChordSumRelative * s);
    }
}

TEST_F(Stress, ZeroLengthShaftsGiveZero)
{
    const Vec3d p(0.3, -4.0, 0.7);
    for (Strategy st : kAll) {
        auto integ = make(st);
        ShaftIntegral r;
        integ->integrate({p, p}, r);
        EXPECT_EQ(r.dampingIntegral, 0.0) << integ->name();
        EXPECT_EQ(r.lengthMm, 0.0);
        integ->integrate({p, p + Vec3d(1e-15, 0, 0)}, r);
        EXPECT_TRUE(std::isfinite(r.dampingIntegral)) << integ->name();
        EXPECT_LE(std::abs(r.dampingIntegral), 1e-2 * 1e-15) << integ->name(); // at most β_max·L
    }
}

TEST_F(Stress, OutsideAndFarAwayShaftsAreAirAndCheap)
{
    for (Strategy st : kAll) {
        auto integ = make(st);
        ShaftIntegral r;
        // 1e6 mm away, 1e6 mm long: clipped to nothing, air all the way.
        const Segment far{{1e6, 1e6, 1e6}, {2e6, 1e6, 1e6}};
        integ->integrate(far, r);
        EXPECT_EQ(r.dampingIntegral, 0.0) << integ->name();
        if (r.labelsValid) {
            EXPECT_NEAR(r.labelLengthMm[0], 1e6, 1e-6) << integ->name();
        }
        // A shaft from far outside straight through the slab: only the slab counts.
        const Segment through{{0.3, 1e6, 0.2}, {0.3, -1e6, 0.2}};
        integ->integrate(through, r);
        const double expected = 2.0 * 8152e-6 + 8.0 * 3696e-6 + 10.0 * 8152e-6;
        // Exact strategies: float β and 2e6 mm of double arithmetic, 1e-6 relative. The
        // marches: the trapezoid rule on each of the four jumps, at most |Δβ|·Δs/2 each.
        const bool march = st == Strategy::MarchNearest || st == Strategy::MarchTrilinear;
        const double jumps = 2.0 * 8152e-6 + 2.0 * (8152e-6 - 3696e-6);
        EXPECT_NEAR(r.dampingIntegral, expected, march ? jumps * 0.25 * kH / 2.0 : 1e-6 * expected) << integ->name();
        // Non-finite or overflowing coordinates: zero, never NaN.
        for (const Segment& bad : {Segment{{std::nan(""), 0, 0}, {0, 0, 0}},
                 Segment{{0, 0, 0}, {std::numeric_limits<double>::infinity(), 0, 0}},
                 Segment{{-1e308, 0, 0}, {1e308, 0, 0}}}) {
            integ->integrate(bad, r);
            EXPECT_EQ(r.dampingIntegral, 0.0) << integ->name();
        }
    }
}

TEST(StressField, NanVoxelsContributeNothing)
{
    volume::initializeOpenVdb();
    auto beta = volume::FloatGrid::create(0.0f);
    beta->setTransform(openvdb::math::Transform::createLinearTransform(0.5));
    for (int j = 0; j < 20; ++j) beta->tree().setValueOn(openvdb::Coord(0, j, 0), 1e-3f);
    beta->tree().setValueOn(openvdb::Coord(0, 7, 0), std::numeric_limits<float>::quiet_NaN());
    beta->tree().setValueOn(openvdb::Coord(0, 8, 0), std::numeric_limits<float>::infinity());
    const MaterialField field(beta, nullptr, volume::TissueTable::builtin());
    for (Strategy st : kAll) {
        IntegratorOptions o{st};
        o.stepMm = 0.05;
        o.trackLabels = false;
        auto integ = makeIntegrator(field, o);
        ShaftIntegral r;
        integ->integrate({{0, -0.25, 0}, {0, 9.75, 0}}, r); // along the column of 20 voxels, 10 mm
        EXPECT_TRUE(std::isfinite(r.dampingIntegral)) << integ->name();
        if (st == Strategy::ExactVoxel || st == Strategy::Profile) {
            EXPECT_NEAR(r.dampingIntegral, 18 * 0.5 * 1e-3, 1e-9) << integ->name(); // two bad voxels read as 0
        }
    }
}

TEST(StressField, HugeSparseVolumeCostsTheVoxelsCrossed)
{
    // 2048³ index extent (more voxels than 32-bit counts hold), two active voxels at
    // opposite corners; a diagonal shaft crosses about 3·2048 voxels, not 2048³.
    volume::initializeOpenVdb();
    auto beta = volume::FloatGrid::create(0.0f);
    beta->setTransform(openvdb::math::Transform::createLinearTransform(1.0));
    beta->tree().setValueOn(openvdb::Coord(0, 0, 0), 2e-3f);
    beta->tree().setValueOn(openvdb::Coord(2047, 2047, 2047), 3e-3f);
    const MaterialField field(beta, nullptr, volume::TissueTable::builtin());
    auto exact = makeIntegrator(field, {Strategy::ExactVoxel, 0.1, false});
    ShaftIntegral r;
    // Along the main diagonal through both voxel centres: each is crossed over sqrt(3) mm.
    exact->integrate({{-0.5, -0.5, -0.5}, {2047.5, 2047.5, 2047.5}}, r);
    EXPECT_NEAR(r.dampingIntegral, std::sqrt(3.0) * (2e-3 + 3e-3), 1e-9);
}

TEST_F(Stress, RandomShaftsStayFiniteAndComplete)
{
    std::mt19937 rng(42);
    std::uniform_real_distribution<double> coord(-40.0, 40.0);
    std::uniform_int_distribution<int> pick(0, 9);
    std::vector<std::unique_ptr<ShaftIntegrator>> integrators;
    for (Strategy st : kAll) integrators.push_back(make(st));
    ShaftIntegral r;
    const double maxBeta = slab->field->maxDamping();
    for (int n = 0; n < 20000; ++n) {
        Vec3d a(coord(rng), coord(rng), coord(rng)), b(coord(rng), coord(rng), coord(rng));
        switch (pick(rng)) { // snap to faces, edges, corners and degenerate cases
        case 0:
            a = (a / kH).array().round() * kH;
            break;
        case 1:
            b = a;
            break;
        case 2:
            b = a + Vec3d(0, 0, 1e-300);
            break;
        case 3:
            b = (b / kH).array().round() * kH;
            a = (a / kH).array().round() * kH;
            break;
        default:
            break;
        }
        for (auto& integ : integrators) {
            integ->integrate({a, b}, r);
            const double length = (b - a).norm();
            ASSERT_TRUE(std::isfinite(r.dampingIntegral)) << integ->name();
            ASSERT_GE(r.dampingIntegral, -1e-18) << integ->name();
            ASSERT_LE(r.dampingIntegral, maxBeta * length * (1.0 + 1e-9) + 1e-18) << integ->name();
            if (r.labelsValid) {
                ASSERT_NEAR(labelSum(r), length, 1e-9 * length + 1e-12) << integ->name();
            }
        }
    }
}

TEST_F(Stress, IntegrationNeverAllocates)
{
    std::vector<std::unique_ptr<ShaftIntegrator>> integrators;
    for (Strategy st : kAll) integrators.push_back(make(st));
    ShaftIntegral r;
    for (auto& integ : integrators) integ->integrate({{0.1, 1.0, 0.2}, {0.1, -15.0, 0.2}}, r); // warm up
    const long before = test::allocations(), freesBefore = test::deallocations();
    for (int n = 0; n < 200; ++n) {
        const double x = 0.01 * n; // moves off the profile's line: rebuilds are included
        for (auto& integ : integrators) integ->integrate({{x, 1.0, 0.2}, {0.1, -15.0 - 0.05 * n, 0.2}}, r);
    }
    EXPECT_EQ(test::allocations() - before, 0);
    EXPECT_EQ(test::deallocations() - freesBefore, 0);
    auto* profile = dynamic_cast<TrajectoryProfile*>(integrators.back().get());
    ASSERT_NE(profile, nullptr);
    EXPECT_GT(profile->rebuilds(), 10u);
}

} // namespace
} // namespace voxhap::haptic
