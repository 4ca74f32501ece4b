// SPDX-License-Identifier: Apache-2.0
/// @file TestTransform.cpp
/// @brief Index <-> world mapping of a Volume on anisotropic, oblique lattices.

#include "common/Tolerances.h"

#include "core/Errors.h"
#include "volume/Volume.h"

#include <Eigen/Geometry>

#include <random>

namespace voxhap::volume {
namespace {

using test::kGeometryRelative;
using test::kRoundTripMm;
using test::nearVec;

Geometry obliqueGeometry()
{
    Geometry g;
    g.spacing = Vec3d(0.7, 1.074, 3.0); // CT-like anisotropy
    g.origin = Vec3d(-251.3, 17.25, -1043.5);
    g.direction = (Eigen::AngleAxisd(0.3, Vec3d(1, 2, 3).normalized()) * Eigen::AngleAxisd(-0.2, Vec3d::UnitX()))
                      .toRotationMatrix();
    return g;
}

TEST(Transform, IndexToWorldFollowsTheAffineDefinition)
{
    const Geometry g = obliqueGeometry();
    const Volume v(g, IndexBox{});
    // world = origin + direction · diag(spacing) · ijk, written out independently.
    const Vec3d ijk(3.0, -2.0, 7.5);
    Vec3d expected = g.origin;
    for (int a = 0; a < 3; ++a) expected += g.direction.col(a) * g.spacing[a] * ijk[a];
    EXPECT_TRUE(nearVec(v.indexToWorld(ijk), expected, kRoundTripMm));
}

TEST(Transform, RoundTripsOnAnisotropicObliqueLattice)
{
    const Volume v(obliqueGeometry(), IndexBox{});
    std::mt19937 rng(12345);
    std::uniform_real_distribution<double> u(-600.0, 600.0);
    for (int n = 0; n < 1000; ++n) {
        const Vec3d ijk(u(rng), u(rng), u(rng));
        EXPECT_TRUE(nearVec(v.worldToIndex(v.indexToWorld(ijk)), ijk, kRoundTripMm));
        const Vec3d xyz(u(rng), u(rng), u(rng));
        EXPECT_TRUE(nearVec(v.indexToWorld(v.worldToIndex(xyz)), xyz, kRoundTripMm));
    }
}

TEST(Transform, GeometryIsRecoveredFromTheTransform)
{
    const Geometry g = obliqueGeometry();
    const Geometry back = geometryOf(*makeTransform(g));
    EXPECT_TRUE(nearVec(back.spacing, g.spacing, kGeometryRelative * 10.0));
    EXPECT_TRUE(nearVec(back.origin, g.origin, kGeometryRelative * 1e3));
    for (int c = 0; c < 3; ++c) {
        EXPECT_TRUE(nearVec(back.direction.col(c), g.direction.col(c), kGeometryRelative));
    }
}

TEST(Transform, AnisotropicChordIsNotIndexLength)
{
    // One voxel step along k is 3 mm, along i 0.7 mm: distances must be taken in world space.
    const Volume v(obliqueGeometry(), IndexBox{});
    EXPECT_NEAR((v.indexToWorld(Vec3d(0, 0, 1)) - v.indexToWorld(Vec3d::Zero())).norm(), 3.0, kRoundTripMm);
    EXPECT_NEAR((v.indexToWorld(Vec3d(1, 0, 0)) - v.indexToWorld(Vec3d::Zero())).norm(), 0.7, kRoundTripMm);
}

TEST(Transform, WorldBoundsIncludeHalfVoxelFaces)
{
    Geometry g;
    g.spacing = Vec3d(0.5, 2.0, 1.0);
    g.origin = Vec3d(10, 20, 30);
    const Volume v(g, IndexBox{Vec3i(0, 0, 0), Vec3i(9, 4, 1)});
    const auto b = v.worldBounds();
    EXPECT_TRUE(nearVec(b[0], Vec3d(10 - 0.25, 20 - 1.0, 30 - 0.5), kRoundTripMm));
    EXPECT_TRUE(nearVec(b[1], Vec3d(10 + 4.5 + 0.25, 20 + 8.0 + 1.0, 30 + 1.0 + 0.5), kRoundTripMm));
    EXPECT_EQ(v.indexBox().voxelCount(), 10 * 5 * 2);
}

TEST(Transform, RejectsDegenerateGeometry)
{
    Geometry g;
    g.spacing = Vec3d(1, 0, 1);
    EXPECT_THROW(makeTransform(g), ValueError);
    g.spacing = Vec3d(1, std::nan(""), 1);
    EXPECT_THROW(makeTransform(g), ValueError);
    g.spacing = Vec3d(1, 1, 1);
    g.direction.col(2) = g.direction.col(0);
    EXPECT_THROW(makeTransform(g), ValueError);
    g.direction = Mat3d::Identity() * 2.0;
    EXPECT_THROW(makeTransform(g), ValueError);
}

} // namespace
} // namespace voxhap::volume
