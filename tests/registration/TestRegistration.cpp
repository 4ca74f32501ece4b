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
#include "registration/detail/MetricStage.h"
#include "registration/detail/SurfaceCheck.h"
#include "volume/Grids.h"
#include "volume/VolumeFile.h"

#include <gtest/gtest.h>
#include <itkBinaryCrossStructuringElement.h>
#include <itkBinaryDilateImageFilter.h>
#include <itkBinaryErodeImageFilter.h>
#include <itkBinaryFillholeImageFilter.h>
#include <itkConnectedComponentImageFilter.h>
#include <itkRelabelComponentImageFilter.h>

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

/// The body mask of bodyAbove, made by ITK's own filters: erosion and dilation by the
/// 6-neighbour cross (outside the image neither body nor air for the erosion, air for
/// the dilation), 6-connected parts ranked by size, and the holes that 6-connected
/// air from the border cannot reach filled.
std::vector<std::uint8_t> itkBodyMask(const LevelImage& image, float threshold, int opening)
{
    using Mask = itk::Image<unsigned char, 3>;
    using Labels = itk::Image<unsigned int, 3>;
    auto toItk = [&](const std::vector<std::uint8_t>& v) {
        auto m = Mask::New();
        Mask::SizeType size;
        for (int a = 0; a < 3; ++a) size[unsigned(a)] = itk::SizeValueType(image.dims[a]);
        m->SetRegions(Mask::RegionType(size));
        m->Allocate();
        std::copy(v.begin(), v.end(), m->GetBufferPointer());
        return m;
    };
    auto fromItk = [&](const Mask* m) {
        return std::vector<std::uint8_t>(m->GetBufferPointer(), m->GetBufferPointer() + image.count());
    };
    std::vector<std::uint8_t> mask(std::size_t(image.count()));
    for (std::size_t q = 0; q < mask.size(); ++q) mask[q] = image.values[q] > threshold ? 1 : 0;
    using Cross = itk::BinaryCrossStructuringElement<unsigned char, 3>;
    Cross cross;
    cross.SetRadius(1);
    cross.CreateStructuringElement();
    Mask::Pointer core = toItk(mask);
    for (int p = 0; p < opening; ++p) {
        auto erode = itk::BinaryErodeImageFilter<Mask, Mask, Cross>::New();
        erode->SetInput(core);
        erode->SetKernel(cross);
        erode->SetErodeValue(1);
        erode->SetBoundaryToForeground(true);
        erode->Update();
        core = erode->GetOutput();
    }
    auto parts = itk::ConnectedComponentImageFilter<Mask, Labels>::New();
    parts->SetInput(core);
    parts->SetFullyConnected(false);
    auto ranked = itk::RelabelComponentImageFilter<Labels, Labels>::New();
    ranked->SetInput(parts->GetOutput());
    ranked->Update();
    std::vector<std::uint8_t> body(mask.size());
    const unsigned* label = ranked->GetOutput()->GetBufferPointer();
    for (std::size_t q = 0; q < body.size(); ++q) body[q] = label[q] == 1 ? 1 : 0; // 1: the largest part
    for (int p = 0; p < opening; ++p) {
        auto dilate = itk::BinaryDilateImageFilter<Mask, Mask, Cross>::New();
        dilate->SetInput(toItk(body));
        dilate->SetKernel(cross);
        dilate->SetDilateValue(1);
        dilate->Update();
        body = fromItk(dilate->GetOutput());
        for (std::size_t q = 0; q < body.size(); ++q) body[q] = body[q] && mask[q];
    }
    auto fill = itk::BinaryFillholeImageFilter<Mask>::New();
    fill->SetInput(toItk(body));
    fill->SetFullyConnected(false);
    fill->SetForegroundValue(1);
    fill->Update();
    return fromItk(fill->GetOutput());
}

// The body mask (the largest part once opened, its holes filled) against ITK's filters
// on random bodies: blobs of every size, thin bridges, cavities, parts on the border.
// Control: the masks differ from the plain threshold, so each step had work to do.
TEST(LevelImage, BodyMaskIsItksLargestOpenedPartWithItsHolesFilled)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int trial = 0; trial < 6; ++trial) {
        LevelImage image;
        image.dims = Vec3i(37 + trial, 29, 23 - trial);
        image.values.assign(std::size_t(image.count()), 0.0f);
        image.body.assign(image.values.size(), 0);
        struct Blob {
            Vec3d c;
            double r, sign;
        };
        std::vector<Blob> blobs;
        for (int b = 0; b < 14; ++b) {
            const Vec3d c(u(rng) * image.dims.x(), u(rng) * image.dims.y(), u(rng) * image.dims.z());
            blobs.push_back({c, 2.0 + 7.0 * u(rng), b % 4 == 3 ? -1.0 : 1.0}); // every 4th digs a cavity
        }
        for (int k = 0; k < image.dims.z(); ++k)
            for (int j = 0; j < image.dims.y(); ++j)
                for (int i = 0; i < image.dims.x(); ++i) {
                    double v = 0.3 * u(rng); // speckle: single voxels and thin bridges above the threshold
                    for (const Blob& b : blobs)
                        v += b.sign * std::exp(-(Vec3d(i, j, k) - b.c).squaredNorm() / (b.r * b.r));
                    image.values[std::size_t(image.index(i, j, k))] = float(v);
                }
        for (int opening : {0, 1, 2}) {
            const std::vector<std::uint8_t> expected = itkBodyMask(image, 0.5f, opening);
            LevelImage mine = image;
            bodyAbove(mine, 0.5f, opening);
            long differ = 0, fromThreshold = 0;
            for (std::size_t q = 0; q < expected.size(); ++q) {
                differ += (mine.body[q] != 0) != (expected[q] != 0);
                fromThreshold += (expected[q] != 0) != (image.values[q] > 0.5f);
            }
            EXPECT_EQ(differ, 0) << "trial " << trial << ", opening " << opening;
            EXPECT_GT(fromThreshold, 0) << "control: trial " << trial << ", opening " << opening;
        }
    }
}

/// A lumbar phantom's CT and a turned, shifted MR of it as 2 mm level images
/// with their bodies, and the true map: the metric tests' pair.
struct LevelPair {
    LevelImage fixed, moving;
    AffineMap truth;
};

LevelPair lumbarLevelPair()
{
    const auto& table = volume::TissueTable::builtin();
    volume::PhantomSpec spec;
    spec.kind = "lumbar";
    volume::GridSpec grid;
    grid.spacing = Vec3d(2, 2, 2);
    const volume::PhantomModel model = volume::phantomModel(spec, table);
    const volume::Volume ct = volume::phantomCtScan(model, grid, table);
    volume::PhantomMrScan scan;
    scan.rotation = test::rotationDeg(Vec3d(5, -8, 12));
    scan.translationMm = Vec3d(6, -4, 10);
    scan.seed = 3;
    volume::PhantomScanTruth truth;
    const volume::Volume mr = volume::phantomMrScan(model, table, scan, &truth);
    LevelPair p;
    p.fixed = blockAverage(ct, Channel::Hu, blockFactors(ct.geometry().spacing, 2.0));
    p.moving = blockAverage(mr, Channel::T1, blockFactors(mr.geometry().spacing, 2.0));
    clampValues(p.fixed, -1000.0f, 2000.0f);
    bodyAbove(p.fixed, -500.0f, 1);
    bodyAbove(p.moving, 0.2f * bodyQuantile(p.moving, 0.9), 1);
    p.truth = AffineMap{truth.linear, truth.offset};
    return p;
}

// The moving image ITK is handed is cropped to its mask's box and a margin
// (MetricPair, kMovingCropVoxels): the metric must be the whole image's to the
// last bit, at the truth and at maps that put samples on the mask's edge and
// past the crop. Control: a crop without its margin changes the metric.
TEST(MetricPair, TheCroppedMovingImageGivesTheWholeImagesMetric)
{
    const LevelPair pair = lumbarLevelPair();
    const LevelImage& fixed = pair.fixed;
    const LevelImage& moving = pair.moving;
    const detail::MetricPair cropped(fixed, moving, 3.0), whole(fixed, moving, 3.0, 1, -1),
        bare(fixed, moving, 3.0, 1, 0);
    detail::StageSettings s;
    s.samples = 4000;
    const Vec3d centre = fixed.bodyCentroid();
    const AffineMap& truthMap = pair.truth;
    int changedByBareCrop = 0;
    for (const Vec3d& shift : {Vec3d(0, 0, 0), Vec3d(8, 0, 0), Vec3d(0, -12, 0), Vec3d(0, 0, 20), Vec3d(-15, 10, -6)}) {
        AffineMap m = truthMap;
        m.offset += shift; // the body slid across the mask's edge by up to 20 mm
        EXPECT_EQ(cropped.metricAt(m, centre, s), whole.metricAt(m, centre, s)) << shift.transpose();
        changedByBareCrop += bare.metricAt(m, centre, s) != whole.metricAt(m, centre, s);
    }
    EXPECT_GT(changedByBareCrop, 0) << "control: without the margin the crop changes the metric";
}

// The metric's samples are split over two work units (MetricPair, OrderedMattes):
// whatever order the threads finish in, every evaluation must give the same
// bits, and the same sums as ITK's serial metric up to their grouping. Control:
// the grouping is visible in the bits (two units do not give one unit's bits),
// so a reduction whose order followed the threads would fail the repeat check;
// with ITK's own reduction (OrderedMattes::giveEachUnitItsOwnSum returning at
// once) this test failed at its first repeat in each of five runs.
TEST(MetricPair, ItsWorkUnitsGiveOneAnswerWhateverTheThreadsTiming)
{
    const LevelPair pair = lumbarLevelPair();
    const LevelImage& fixed = pair.fixed;
    const LevelImage& moving = pair.moving;
    const detail::MetricPair one(fixed, moving, 3.0, 1), two(fixed, moving, 3.0, 2);
    detail::StageSettings s;
    s.samples = 20000; // the finest level's count: each unit fills and empties its buffer many times
    const Vec3d centre = fixed.bodyCentroid();
    AffineMap m = pair.truth;
    m.offset += Vec3d(3, -2, 4); // off the optimum, so that every derivative is far from zero
    const auto serial = one.metricAndDerivativeAt(m, centre, s);
    const auto first = two.metricAndDerivativeAt(m, centre, s);
    ASSERT_EQ(first.second.size(), 6u);
    for (int repeat = 0; repeat < 30; ++repeat) {
        const auto again = two.metricAndDerivativeAt(m, centre, s);
        ASSERT_EQ(again.first, first.first) << "repeat " << repeat;
        ASSERT_EQ(again.second, first.second) << "repeat " << repeat;
    }
    // Up to grouping: 20000 samples' sums in double carry relative rounding
    // of about 20000 · 2⁻⁵³ ≈ 2·10⁻¹², far below 10⁻⁹.
    double norm = 0.0;
    for (double d : serial.second) norm = std::max(norm, std::abs(d));
    EXPECT_NEAR(first.first, serial.first, 1e-9 * std::abs(serial.first));
    for (std::size_t i = 0; i < serial.second.size(); ++i) {
        EXPECT_NEAR(first.second[i], serial.second[i], 1e-9 * norm) << "parameter " << i;
    }
    EXPECT_TRUE(first.first != serial.first || first.second != serial.second)
        << "control: two units group the sums otherwise, and the bits show it";
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
                if (on) {
                    ASSERT_FLOAT_EQ(dst.getValue(c), src.getValue(s)) << c;
                }
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
