// SPDX-License-Identifier: Apache-2.0
/// @file TestDistanceTransform.cpp
/// @brief The exact EDT against brute force on anisotropic voxels; morphology
/// against the Euclidean ball it must give; hole filling and components.

#include "segmentation/lattice/Components.h"
#include "segmentation/lattice/DistanceTransform.h"
#include "segmentation/lattice/Morphology.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace voxhap::segmentation {
namespace {

// Squared distances are sums of three squares of multiples of the spacing; the
// transform works in double and stores float: relative error of float rounding.
constexpr double kFloatRelTol = 1e-6;

Lattice lattice(int nx, int ny, int nz, const Vec3d& spacing)
{
    Lattice l;
    l.dims = Vec3i(nx, ny, nz);
    l.spacing = spacing;
    return l;
}

double bruteForce(const Lattice& lat, const Mask& f, std::size_t n, Span span)
{
    const Vec3i p = lat.position(n);
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t m = 0; m < f.size(); ++m) {
        if (!f[m]) continue;
        const Vec3i q = lat.position(m);
        if (span == Span::Slice && q[lat.sliceAxis] != p[lat.sliceAxis]) continue;
        best = std::min(best, ((p - q).cast<double>().cwiseProduct(lat.spacing)).squaredNorm());
    }
    return best;
}

TEST(DistanceTransform, MatchesBruteForceOnAnisotropicVoxels)
{
    const Lattice lat =
        lattice(17, 13, 9, Vec3d(1.07421875, 0.7, 3.0)); // the real CT's 1.07 x 1.07 x 3 mm, and a third
    std::mt19937 rng(7);
    Mask f(lat.size(), 0);
    for (auto& x : f) x = (rng() % 23 == 0) ? 1 : 0;
    for (Span span : {Span::Volume, Span::Slice}) {
        const std::vector<float> d2 = squaredDistance(lat, f, span);
        for (std::size_t n = 0; n < f.size(); ++n) {
            const double expected = bruteForce(lat, f, n, span);
            if (std::isinf(expected)) {
                EXPECT_TRUE(std::isinf(d2[n])) << n;
            } else {
                EXPECT_NEAR(d2[n], expected, kFloatRelTol * std::max(1.0, expected)) << "voxel " << n;
            }
        }
    }
}

TEST(DistanceTransform, EmptyFeatureSetIsInfiniteEverywhere)
{
    const Lattice lat = lattice(5, 4, 3, Vec3d(1, 1, 1));
    const std::vector<float> d2 = squaredDistance(lat, Mask(lat.size(), 0), Span::Volume);
    for (float x : d2) EXPECT_TRUE(std::isinf(x));
}

TEST(Morphology, DilatingOneVoxelGivesTheEuclideanBallInMillimetres)
{
    const Lattice lat = lattice(31, 31, 11, Vec3d(0.5, 0.5, 2.0));
    Mask m(lat.size(), 0);
    const Vec3i c(15, 15, 5);
    m[lat.index(c.x(), c.y(), c.z())] = 1;
    const double r = 4.2;
    const Mask ball = dilate(lat, m, r, Span::Volume);
    for (std::size_t n = 0; n < m.size(); ++n) {
        const double d = ((lat.position(n) - c).cast<double>().cwiseProduct(lat.spacing)).norm();
        EXPECT_EQ(ball[n] != 0, d <= r) << n;
    }
    // Erosion by 1 mm of the ball: voxels whose nearest outside centre is farther than 1 mm.
    const Mask inner = erode(lat, ball, 1.0, Span::Volume);
    for (std::size_t n = 0; n < m.size(); ++n) {
        if (inner[n]) {
            EXPECT_TRUE(ball[n]) << n;
        }
    }
    EXPECT_TRUE(inner[lat.index(c.x(), c.y(), c.z())]);
    EXPECT_FALSE(inner[lat.index(c.x() + 8, c.y(), c.z())]); // 4.0 mm out: its neighbour at 4.5 mm is outside the ball
}

TEST(Morphology, HolesAreFilledPerSliceButOpenCavitiesAreNot)
{
    const Lattice lat = lattice(12, 12, 2, Vec3d(1, 1, 1));
    Mask m(lat.size(), 0);
    for (int k = 0; k < 2; ++k) {
        for (int i = 2; i <= 9; ++i) {
            for (int j = 2; j <= 9; ++j) {
                const bool ring = i == 2 || i == 9 || j == 2 || j == 9;
                m[lat.index(i, j, k)] = ring ? 1 : 0;
            }
        }
    }
    m[lat.index(2, 5, 1)] = 0; // slice 1's ring has a gap: its cavity is open
    fillHolesPerSlice(lat, m);
    EXPECT_TRUE(m[lat.index(5, 5, 0)]);
    EXPECT_FALSE(m[lat.index(5, 5, 1)]);
    EXPECT_FALSE(m[lat.index(0, 0, 0)]);
}

/// The reference for the fill: every complement pixel reachable from its
/// slice's border through the complement, 4-connected, found by a breadth-first
/// search one pixel at a time (independent of the scanline fill under test).
Mask holesFilledByPixelSearch(const Lattice& lat, Mask m)
{
    const int nx = lat.dims[0], ny = lat.dims[1], nz = lat.dims[2];
    for (int k = 0; k < nz; ++k) {
        std::vector<std::uint8_t> reached(std::size_t(nx) * std::size_t(ny), 0);
        std::vector<std::pair<int, int>> queue;
        const auto visit = [&](int i, int j) {
            if (i < 0 || j < 0 || i >= nx || j >= ny) return;
            if (reached[std::size_t(i) + std::size_t(nx) * std::size_t(j)] || m[lat.index(i, j, k)]) return;
            reached[std::size_t(i) + std::size_t(nx) * std::size_t(j)] = 1;
            queue.emplace_back(i, j);
        };
        for (int i = 0; i < nx; ++i) visit(i, 0), visit(i, ny - 1);
        for (int j = 0; j < ny; ++j) visit(0, j), visit(nx - 1, j);
        for (std::size_t q = 0; q < queue.size(); ++q) {
            const auto [i, j] = queue[q];
            visit(i - 1, j), visit(i + 1, j), visit(i, j - 1), visit(i, j + 1);
        }
        for (int j = 0; j < ny; ++j) {
            for (int i = 0; i < nx; ++i) {
                if (!reached[std::size_t(i) + std::size_t(nx) * std::size_t(j)]) m[lat.index(i, j, k)] = 1;
            }
        }
    }
    return m;
}

TEST(Morphology, FilledHolesEqualAPixelByPixelSearchOnRandomMasks)
{
    // Random masks from sparse to dense (near 0.4 the open pixels percolate
    // only in part: many enclosed pockets, winding runs), slices of odd
    // shapes so rows and columns differ, and a fixed seed so a failure repeats.
    std::mt19937 rng(20261127);
    for (const double density : {0.05, 0.3, 0.4, 0.45, 0.6}) {
        for (const auto& [nx, ny] :
            {std::pair{1, 7}, std::pair{7, 1}, std::pair{2, 2}, std::pair{23, 17}, std::pair{40, 64}}) {
            SCOPED_TRACE(std::to_string(density) + " " + std::to_string(nx) + "x" + std::to_string(ny));
            const Lattice lat = lattice(nx, ny, 3, Vec3d(1, 1, 1));
            std::bernoulli_distribution in(density);
            Mask m(lat.size(), 0);
            for (auto& x : m) x = in(rng) ? 1 : 0;
            const Mask expected = holesFilledByPixelSearch(lat, m);
            fillHolesPerSlice(lat, m);
            EXPECT_EQ(m, expected);
        }
    }
}

TEST(Components, CountsSizesAndConnectivity)
{
    const Lattice lat = lattice(6, 6, 3, Vec3d(1, 1, 1));
    Mask m(lat.size(), 0);
    m[lat.index(0, 0, 0)] = m[lat.index(1, 0, 0)] = 1; // two voxels, face-connected
    m[lat.index(3, 3, 0)] = m[lat.index(3, 3, 1)] = 1; // joined across slices
    m[lat.index(5, 5, 2)] = m[lat.index(4, 4, 2)] = 1; // diagonal only: two components
    const Components v = connectedComponents(lat, m, Span::Volume);
    EXPECT_EQ(v.list.size(), 4u);
    const Components s = connectedComponents(lat, m, Span::Slice);
    EXPECT_EQ(s.list.size(), 5u); // the cross-slice pair splits
    EXPECT_EQ(v.list[0].voxels, 2);
    const Mask big = largestComponent(lat, m);
    EXPECT_EQ(std::count(big.begin(), big.end(), 1), 2);
}

} // namespace
} // namespace voxhap::segmentation
