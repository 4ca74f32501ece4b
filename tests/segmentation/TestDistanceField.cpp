// SPDX-License-Identifier: Apache-2.0
/// @file TestDistanceField.cpp
/// @brief The signed distance field of a voxelised sphere against the sphere's
/// closed form, |p − c| − R, within half a voxel (issue: "exact to half a voxel").

#include "segmentation/DistanceField.h"
#include "volume/Grids.h"

#include <gtest/gtest.h>

#include <openvdb/openvdb.h>

#include <cmath>

namespace voxhap::segmentation {
namespace {

TEST(DistanceField, SphereWithinHalfAVoxelOfTheClosedForm)
{
    openvdb::initialize();
    const double h = 0.5, radius = 10.3, band = 6.0;
    Lattice lat;
    lat.dims = Vec3i(61, 61, 61);
    lat.spacing = Vec3d(h, h, h);
    const Vec3d centre(15.1, 14.9, 15.2); // off the lattice, so the surface cuts voxels at every fraction
    std::vector<std::int32_t> labels(lat.size(), 0);
    for (std::size_t n = 0; n < labels.size(); ++n) {
        if ((lat.position(n).cast<double>() * h - centre).norm() < radius) labels[n] = 14;
    }
    const auto grid = openvdb::gridPtrCast<volume::FloatGrid>(signedDistanceField(lat, labels, 14, band));
    ASSERT_TRUE(grid);
    auto acc = grid->getConstAccessor();
    double worst = 0;
    int checked = 0;
    for (std::size_t n = 0; n < labels.size(); ++n) {
        const Vec3i p = lat.position(n);
        const double exact = (p.cast<double>() * h - centre).norm() - radius;
        const float got = acc.getValue(openvdb::Coord(p.x(), p.y(), p.z()));
        if (std::abs(exact) < band - h) {
            worst = std::max(worst, std::abs(got - exact));
            ++checked;
            ASSERT_EQ(got < 0, labels[n] != 0) << "sign at " << p.transpose();
        } else if (exact > band + 0.5 * h) { // the field may undershoot by half a voxel
            EXPECT_EQ(got, float(band));     // the far outside reads as the band
        }
    }
    EXPECT_GT(checked, 10000);
    EXPECT_LE(worst, 0.5 * h) << "largest error " << worst << " mm";
}

} // namespace
} // namespace voxhap::segmentation
