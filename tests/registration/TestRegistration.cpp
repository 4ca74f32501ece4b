// SPDX-License-Identifier: Apache-2.0
/// @file TestRegistration.cpp
/// @brief The registration's pieces against independent references: the 24
/// axis turns against their definition, block averages against a brute-force
/// mean, resampling against an exact shift, the transform file against ITK's
/// own reader, and the phantom pairs against the transforms they were made with.

#include "common/TempDirTest.h"
#include "core/Errors.h"
#include "phantoms/PhantomScans.h"
#include "registration/AffineMap.h"
#include "registration/LevelImage.h"
#include "registration/Registration.h"
#include "registration/RegistrationFixtures.h"
#include "registration/Resample.h"
#include "registration/TransformFile.h"
#include "registration/detail/SurfaceCheck.h"
#include "volume/Grids.h"
#include "volume/VolumeFile.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

namespace voxhap::registration {
namespace {

using volume::Channel;
using volume::FloatGrid;

TEST(AxisTurns, AreTheTwentyFourProperRotationsOfTheCube)
{
    const auto turns = axisTurns();
    ASSERT_EQ(turns.size(), 24u); // the rotation group of the cube has order 24 (48 with reflections)
    EXPECT_TRUE(turns.front().isIdentity());
    std::set<std::vector<int>> distinct;
    for (const Mat3d& r : turns) {
        EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
        EXPECT_TRUE((r * r.transpose()).isIdentity(1e-12));
        std::vector<int> key;
        for (int i = 0; i < 9; ++i) key.push_back(int(std::lround(r.data()[i])));
        distinct.insert(key);
    }
    EXPECT_EQ(distinct.size(), 24u);
}

TEST(AxisTurns, NamesGiveTheAngleAndTheAnatomicalAxis)
{
    EXPECT_EQ(describeRotation(Mat3d::Identity()), "identity");
    // Head first against feet first, both supine: x and z reverse, y stays.
    EXPECT_EQ(describeRotation(Vec3d(-1, 1, -1).asDiagonal()), "180° about A–P");
    EXPECT_EQ(describeRotation(Vec3d(1, -1, -1).asDiagonal()), "180° about L–R");
    EXPECT_EQ(describeRotation(test::rotationDeg(Vec3d(0, 0, 90))), "90° about +S–I");
    Mat3d cyclic;
    cyclic << 0, 0, 1, 1, 0, 0, 0, 1, 0;
    EXPECT_EQ(describeRotation(cyclic), "120° about (0.58, 0.58, 0.58)");
}

TEST(AffineMap, InverseAndCompositionUndoEachOther)
{
    const AffineMap a = AffineMap::rotationAbout(test::rotationDeg(Vec3d(10, -20, 30)), Vec3d(5, 6, 7), Vec3d(1, 2, 3));
    const Vec3d x(11, -4, 9);
    EXPECT_LT((a.inverse().apply(a.apply(x)) - x).norm(), 1e-12);
    EXPECT_LT((a.after(a.inverse()).apply(x) - x).norm(), 1e-12);
    // rotationAbout keeps its centre fixed (before the shift).
    EXPECT_LT((a.apply(Vec3d(5, 6, 7)) - Vec3d(6, 8, 10)).norm(), 1e-12);
}

/// A sparse grid of random values in a random third of its box.
volume::Volume randomVolume(const Vec3d& spacing, const Vec3i& dims, std::uint32_t seed)
{
    volume::Geometry g;
    g.spacing = spacing;
    g.origin = Vec3d(-10, 20, 5);
    g.direction = test::rotationDeg(Vec3d(0, 0, 30));
    volume::Volume v(g, volume::IndexBox{Vec3i::Zero(), dims - Vec3i::Ones()});
    auto grid = FloatGrid::create(volume::kAirT1);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> value(100.0f, 2000.0f);
    std::bernoulli_distribution on(1.0 / 3.0);
    auto acc = grid->getAccessor();
    for (int k = 0; k < dims.z(); ++k)
        for (int j = 0; j < dims.y(); ++j)
            for (int i = 0; i < dims.x(); ++i)
                if (on(rng)) acc.setValueOn(openvdb::Coord(i, j, k), value(rng));
    v.setGrid(Channel::T1, grid);
    return v;
}

TEST(LevelImage, EachVoxelIsTheMeanOfItsBlockWithAirAtTheBackground)
{
    const volume::Volume v = randomVolume(Vec3d(0.5, 0.7, 1.5), Vec3i(23, 17, 9), 7);
    const Vec3i f(3, 2, 2);
    const LevelImage li = blockAverage(v, Channel::T1, f);
    ASSERT_EQ(li.dims, Vec3i(7, 8, 4)); // partial blocks at the far edge dropped
    auto acc = volume::t1Grid(v)->getConstAccessor();
    for (int k = 0; k < li.dims.z(); ++k)
        for (int j = 0; j < li.dims.y(); ++j)
            for (int i = 0; i < li.dims.x(); ++i) {
                double sum = 0;
                int active = 0;
                for (int c = 0; c < f.z(); ++c)
                    for (int b = 0; b < f.y(); ++b)
                        for (int a = 0; a < f.x(); ++a) {
                            const openvdb::Coord q(i * f.x() + a, j * f.y() + b, k * f.z() + c);
                            sum += acc.getValue(q); // the background (0) where inactive
                            active += acc.isValueOn(q);
                        }
                const auto n = std::size_t(li.index(i, j, k));
                EXPECT_NEAR(li.values[n], sum / f.prod(), 1e-3) << i << ',' << j << ',' << k;
                EXPECT_EQ(li.body[n], 2 * active >= f.prod() ? 1 : 0);
            }
    // The level's voxel centre is the block's centre in world space.
    const Vec3d blockCentre = v.indexToWorld(Vec3d(1.0, 0.5, 0.5)); // block (0,0,0): indices 0..2, 0..1, 0..1
    EXPECT_LT((li.world(Vec3d::Zero()) - blockCentre).norm(), 1e-12);
}

TEST(Resample, AShiftByWholeVoxelsCopiesTheValuesExactly)
{
    // The CT and the MR share a lattice; the MR sees the body 2, −1 and 3 voxels further on.
    const volume::Volume mr = randomVolume(Vec3d(1.0, 1.0, 2.0), Vec3i(20, 18, 12), 3);
    volume::Volume ct(mr.geometry(), mr.indexBox());
    const Vec3i shift(2, -1, 3);
    const Vec3d worldShift = mr.geometry().direction * mr.geometry().spacing.cwiseProduct(shift.cast<double>());
    const AffineMap mrFromCt{Mat3d::Identity(), worldShift};
    ResampleReport report;
    const auto out = openvdb::gridPtrCast<FloatGrid>(resampleOnto(ct, mr, Channel::T1, mrFromCt, &report));
    ASSERT_TRUE(out);
    auto src = volume::t1Grid(mr)->getConstAccessor();
    auto dst = out->getConstAccessor();
    std::int64_t expectedActive = 0;
    const auto& box = ct.indexBox();
    for (int k = box.min.z(); k <= box.max.z(); ++k)
        for (int j = box.min.y(); j <= box.max.y(); ++j)
            for (int i = box.min.x(); i <= box.max.x(); ++i) {
                const openvdb::Coord c(i, j, k), s(i + shift.x(), j + shift.y(), k + shift.z());
                const bool on = src.isValueOn(s);
                expectedActive += on;
                ASSERT_EQ(dst.isValueOn(c), on) << c;
                if (on) ASSERT_FLOAT_EQ(dst.getValue(c), src.getValue(s)) << c;
            }
    EXPECT_EQ(report.activeVoxels, expectedActive);
    EXPECT_GT(expectedActive, 0);
}

TEST(TransformFile, ItksOwnReaderReadsBackTheMapWritten)
{
    const AffineMap a{
        test::rotationDeg(Vec3d(3, -7, 12)) * Vec3d(1.01, 0.98, 1.02).asDiagonal(), Vec3d(12.5, -3.25, 40.0)};
    const std::string text = itkTransformText(a);
    EXPECT_NE(text.find("#Insight Transform File V1.0"), std::string::npos) << text;
    EXPECT_NE(text.find("Transform: AffineTransform_double_3_3"), std::string::npos) << text;
    const AffineMap b = parseItkTransform(text, "test");
    EXPECT_LT((a.matrix() - b.matrix()).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_THROW(parseItkTransform("not a transform", "test"), IoError);
}

} // namespace
} // namespace voxhap::registration
