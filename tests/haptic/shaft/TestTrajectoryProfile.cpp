// SPDX-License-Identifier: Apache-2.0
/// @file TestTrajectoryProfile.cpp
/// @brief The profile's guarantees: exact on the line, off the line within a
/// brute-force worst case computed from the voxels (and within its documented
/// bound), rebuilt beyond the tolerance, labels as the traversal.

#include "common/Phantom.h"
#include "common/Tolerances.h"

#include "haptic/materials/FieldGrids.h"
#include "haptic/shaft/ShaftIntegration.h"
#include "haptic/shaft/TrajectoryProfile.h"
#include "volume/Grids.h"

#include "core/Errors.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace voxhap::haptic {
namespace {

using test::kExactRelative;

class Profile : public testing::Test {
protected:
    static void SetUpTestSuite()
    {
        volume::LumbarParams p; // vertebrae: interfaces in every direction
        p.grid.spacing = Vec3d(0.5, 0.4, 0.6);
        fixture = std::make_unique<test::FieldFixture>(
            test::makeFieldFixture(volume::lumbarModel(p, volume::TissueTable::builtin()), p.grid));
    }
    static void TearDownTestSuite() { fixture.reset(); }
    static inline std::unique_ptr<test::FieldFixture> fixture;
    static constexpr double kTolerance = 0.05;
    /// Round-off of sums over ~300 voxel runs of products of doubles: 1e-12 relative.
    static constexpr double kRoundOff = 1e-12;
};

/// Shaft directions into the back: cranial tilts and lateral tilts of a few degrees.
std::vector<std::pair<Vec3d, Vec3d>> paths()
{
    std::vector<std::pair<Vec3d, Vec3d>> out;
    for (double tilt : {0.0, 8.0, 15.0, 25.0}) {
        for (double az : {0.0, 70.0, 200.0}) {
            const Vec3d u = Eigen::AngleAxisd(degToRad(az), Vec3d::UnitY()) *
                (Eigen::AngleAxisd(degToRad(tilt), Vec3d::UnitX()) * Vec3d(0, -1, 0));
            out.emplace_back(Vec3d(0.31, 0.0, -0.17), u);
        }
    }
    return out;
}

TEST_F(Profile, OnTheLineEqualsTheExactTraversalLabelsIncluded)
{
    TrajectoryProfile profile(*fixture->field, kTolerance, 150.0, true);
    auto exact = makeIntegrator(*fixture->field, {Strategy::ExactVoxel});
    ShaftIntegral a, b;
    for (const auto& [entry, u] : paths()) {
        ASSERT_TRUE(profile.lock(entry, u));
        for (double s = 0.0; s <= 90.0; s += 0.737) {
            const Segment seg{entry, entry + s * u};
            profile.integrate(seg, a);
            exact->integrate(seg, b);
            ASSERT_NEAR(a.dampingIntegral, b.dampingIntegral, kExactRelative * b.dampingIntegral + 1e-15);
            for (int l = 0; l < kMaxLabels; ++l) {
                ASSERT_NEAR(a.labelLengthMm[std::size_t(l)], b.labelLengthMm[std::size_t(l)], 1e-9) << "label " << l;
                if (b.firstHitMm[std::size_t(l)] == kNotHit) {
                    ASSERT_EQ(a.firstHitMm[std::size_t(l)], kNotHit) << "label " << l << " s " << s;
                } else {
                    ASSERT_NEAR(a.firstHitMm[std::size_t(l)], b.firstHitMm[std::size_t(l)], 1e-9) << "label " << l;
                }
            }
        }
    }
    // The target: within 1e-6 N of exact on a locked path, at 10 mm/s.
    EXPECT_LE(std::abs(a.dampingForceN(10.0) - b.dampingForceN(10.0)), 1e-6);
}

/// Brute-force worst case of |∫β over a shaft − ∫β over the line| for every shaft whose
/// points lie within @p delta of the line from @p a to @p b, from the voxel field itself
/// (not from the profile's bound). With σ the coordinate along the line and x(σ) the
/// shaft point over p(σ), |x(σ) − p(σ)| ≤ δ and dl = (ℓ'/ℓ)·dσ, so the difference is at
/// most (ℓ'/ℓ)·∫ |β(x(σ)) − β(p(σ))| dσ. Each step of @p ds along the line contributes
/// ds·(max β − min β) over the voxels meeting the step's bounding box widened by δ:
/// both x(σ) and p(σ) lie in that box for every σ of the step, so the sum is a strict
/// upper bound, however the voxels are cut (no sampling can miss a corner).
double bruteForceWorstCase(const volume::FloatGrid& beta, const Vec3d& a, const Vec3d& b, double delta, double scale)
{
    const double length = (b - a).norm();
    if (!(length > 0.0)) return 0.0;
    const Vec3d u = (b - a) / length;
    constexpr double ds = 0.025; // mm: h/16 of the smallest voxel side (0.4 mm)
    auto acc = beta.getConstAccessor();
    double sum = 0.0;
    for (double s0 = 0.0; s0 < length; s0 += ds) {
        const double s1 = std::min(s0 + ds, length);
        const Vec3d p0 = a + s0 * u, p1 = a + s1 * u;
        const Vec3d lo = p0.cwiseMin(p1) - Vec3d::Constant(delta), hi = p0.cwiseMax(p1) + Vec3d::Constant(delta);
        // Voxel i spans index coordinates [i − 0.5, i + 0.5] (centres on the lattice).
        const openvdb::Vec3d ilo = beta.transform().worldToIndex(volume::toVdb(lo));
        const openvdb::Vec3d ihi = beta.transform().worldToIndex(volume::toVdb(hi));
        double mn = std::numeric_limits<double>::infinity(), mx = -mn;
        for (int k = int(std::floor(ilo.z() + 0.5)); k <= int(std::floor(ihi.z() + 0.5)); ++k) {
            for (int j = int(std::floor(ilo.y() + 0.5)); j <= int(std::floor(ihi.y() + 0.5)); ++j) {
                for (int i = int(std::floor(ilo.x() + 0.5)); i <= int(std::floor(ihi.x() + 0.5)); ++i) {
                    const double v = acc.getValue(openvdb::Coord(i, j, k));
                    mn = std::min(mn, v), mx = std::max(mx, v);
                }
            }
        }
        sum += (s1 - s0) * (mx - mn);
    }
    return scale * sum;
}

TEST_F(Profile, OffTheLineWithinTheBruteForceWorstCase)
{
    TrajectoryProfile profile(*fixture->field, kTolerance, 150.0, false);
    auto exact = makeIntegrator(*fixture->field, {Strategy::ExactVoxel, 0.125, false});
    const auto beta = detail::dampingGrid(*fixture->field);
    ASSERT_TRUE(beta);
    ASSERT_TRUE(beta->transform().isLinear() && !beta->transform().hasUniformScale()); // axis-aligned 0.5 × 0.4 × 0.6
    std::mt19937 rng(2024);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    ShaftIntegral a, b;
    int nonZeroWorst = 0, zeroError = 0, count = 0;
    double largestShare = 0.0; // the largest error as a share of its worst case
    for (const auto& [entry, u] : paths()) {
        ASSERT_TRUE(profile.lock(entry, u));
        const auto rebuilds = profile.rebuilds();
        const Vec3d side1 = u.unitOrthogonal(), side2 = u.cross(side1);
        const auto offset = [&] {
            const double r = kTolerance * std::sqrt(unit(rng)), phi = 2.0 * kPi * unit(rng);
            return r * (std::cos(phi) * side1 + std::sin(phi) * side2);
        };
        for (int n = 0; n < 60; ++n) {
            const double s = 90.0 * unit(rng);
            const Segment seg{entry + offset(), entry + s * u + offset()};
            ASSERT_TRUE(profile.covers(seg));
            profile.integrate(seg, a);
            exact->integrate(seg, b);
            const double scale = s > 0.0 ? (seg.tip - seg.entry).norm() / s : 1.0; // ℓ'/ℓ
            const double worst = bruteForceWorstCase(*beta, entry, entry + s * u, kTolerance, scale);
            const double error = std::abs(a.dampingIntegral - b.dampingIntegral);
            // kRoundOff: round-off in the ℓ'/ℓ rescaling and the cumulative sums (a few
            // ulps over ~300 runs) and in the brute-force sum itself, 1e-12 relative.
            ASSERT_LE(error, worst + kRoundOff * b.dampingIntegral) << "s " << s;
            // The documented guarantee (TrajectoryProfile.h) holds as well.
            ASSERT_LE(error, profile.errorBound(seg) + kRoundOff * b.dampingIntegral) << "s " << s;
            if (worst > 0.0) largestShare = std::max(largestShare, error / worst);
            nonZeroWorst += worst > 0.0;
            zeroError += a.dampingIntegral == b.dampingIntegral;
            ++count;
        }
        EXPECT_EQ(profile.rebuilds(), rebuilds);
    }
    EXPECT_GT(nonZeroWorst, 0);  // the shafts do cross interfaces
    EXPECT_LT(zeroError, count); // and the off-line error is not trivially zero
    // The worst case is not vacuous: some shaft comes within a factor of 20 of it.
    EXPECT_GT(largestShare, 0.05);
}

TEST_F(Profile, LeavingTheToleranceRebuilds)
{
    TrajectoryProfile profile(*fixture->field, kTolerance, 150.0, true);
    auto exact = makeIntegrator(*fixture->field, {Strategy::ExactVoxel});
    ShaftIntegral a, b;
    const Vec3d entry(0.31, 0.0, -0.17), u(0, -1, 0);
    profile.integrate({entry, entry + 40.0 * u}, a);
    EXPECT_EQ(profile.rebuilds(), 1u);
    profile.integrate({entry, entry + 50.0 * u}, a); // further along the same line
    EXPECT_EQ(profile.rebuilds(), 1u);
    const Segment moved{entry + Vec3d(0.2, 0, 0), entry + Vec3d(0.2, 0, 0) + 50.0 * u}; // 0.2 mm > tolerance
    EXPECT_FALSE(profile.covers(moved));
    profile.integrate(moved, a);
    EXPECT_EQ(profile.rebuilds(), 2u);
    exact->integrate(moved, b);
    EXPECT_NEAR(a.dampingIntegral, b.dampingIntegral, kExactRelative * b.dampingIntegral);
}

TEST_F(Profile, DegenerateInputGivesZero)
{
    TrajectoryProfile profile(*fixture->field, kTolerance, 150.0, true);
    ShaftIntegral out;
    const Vec3d p(0.3, -10.0, 0.2);
    profile.integrate({p, p}, out);
    EXPECT_EQ(out.dampingIntegral, 0.0);
    profile.integrate({p, Vec3d(std::nan(""), 0, 0)}, out);
    EXPECT_EQ(out.dampingIntegral, 0.0);
    // Locked, a non-finite entry or tip gives zero too (integrate() finds a
    // non-finite entry from its projection on the line: every axis, either sign).
    ASSERT_TRUE(profile.lock(p, Vec3d(0, -1, 0)));
    const double inf = std::numeric_limits<double>::infinity();
    for (int axis = 0; axis < 3; ++axis) {
        for (const double bad : {std::nan(""), inf, -inf}) {
            Vec3d wrong = p;
            wrong[axis] = bad;
            profile.integrate({wrong, p + Vec3d(0, -10, 0)}, out);
            EXPECT_EQ(out.dampingIntegral, 0.0) << "entry, axis " << axis << " value " << bad;
            EXPECT_EQ(out.lengthMm, 0.0);
            profile.integrate({p, wrong}, out);
            EXPECT_EQ(out.dampingIntegral, 0.0) << "tip, axis " << axis << " value " << bad;
            EXPECT_EQ(out.lengthMm, 0.0);
        }
    }
    profile.integrate({p, p + Vec3d(0, -10, 0)}, out); // and the line still answers
    EXPECT_GT(out.dampingIntegral, 0.0);
    EXPECT_FALSE(profile.lock(p, Vec3d::Zero()));
    EXPECT_THROW(TrajectoryProfile(*fixture->field, 1.0, 150.0, true), ValueError); // tolerance >= h/2
}

} // namespace
} // namespace voxhap::haptic
