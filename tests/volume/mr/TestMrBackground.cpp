// SPDX-License-Identifier: Apache-2.0
/// @file TestMrBackground.cpp
/// @brief The MR background rule (volume/mr/MrBackground.h) on synthetic heads in
/// Rayleigh noise of known σ, on masked and air-free images, and on the shared
/// real MR series.

#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/dicom/DicomSeries.h"
#include "volume/mr/MrBackground.h"

#include "common/SharedData.h"

#include <openvdb/tools/Prune.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <vector>

// A named namespace: this file is compiled in a unity batch with other tests.
namespace mrbackground_test {

using namespace voxhap::volume;

/// σ of the synthetic noise [scanner units].
constexpr double kSigma = 10.0;
/// Tissue signal [scanner units]: SNR 40, a typical T1-weighted white matter.
constexpr double kTissue = 400.0;
/// Synthetic volumes: 64³ voxels.
constexpr int kSize = 64;

/// Tolerance on σ̂/σ − 1. The ML estimate of a Rayleigh σ from n samples has a
/// relative standard error of 1/(2√n); the partial histogram (below 2 modes,
/// 86 % of the samples) and the binning cost less than a factor 2 of that.
/// With n ≈ 2·10⁵ noise voxels this is about 0.2 %; the ventricle's Rician
/// values (about 0.5 % of the fit range) bias σ̂ up by at most as much.
/// 2 % is more than 5 standard errors plus that bias.
constexpr double kSigmaRelTolerance = 0.02;

/// Rician magnitude of signal @p a with per-channel noise @p sigma, rounded to
/// an integer as scanners store it (a = 0: Rayleigh noise).
float rician(double a, double sigma, std::mt19937& rng)
{
    std::normal_distribution<double> noise(0.0, sigma);
    const double re = a + noise(rng), im = noise(rng);
    return float(std::round(std::hypot(re, im)));
}

IndexBox cube(int n) { return IndexBox{voxhap::Vec3i(0, 0, 0), voxhap::Vec3i(n - 1, n - 1, n - 1)}; }

/// A dense image as a sparse grid with every voxel active (as the loader
/// leaves a magnitude image today), from value(x, y, z).
FloatGrid::Ptr denseGrid(const IndexBox& box, const std::function<float(int, int, int)>& value)
{
    initializeOpenVdb();
    auto grid = FloatGrid::create(kAirIntensity);
    auto acc = grid->getAccessor();
    for (int z = box.min.z(); z <= box.max.z(); ++z) {
        for (int y = box.min.y(); y <= box.max.y(); ++y) {
            for (int x = box.min.x(); x <= box.max.x(); ++x) acc.setValueOn(openvdb::Coord(x, y, z), value(x, y, z));
        }
    }
    return grid;
}

/// The synthetic head: an ellipsoid of tissue (semi-axes 24, 20, 22 voxels)
/// centred in the cube, with a dark ventricle (radius 6, Rician signal σ,
/// below any noise threshold) inside.
struct Head {
    static constexpr double kCentre = (kSize - 1) / 2.0;
    static double ellipsoid(int x, int y, int z) // < 1 inside
    {
        const double dx = (x - kCentre) / 24, dy = (y - kCentre) / 20, dz = (z - kCentre) / 22;
        return dx * dx + dy * dy + dz * dz;
    }
    static bool ventricle(int x, int y, int z)
    {
        const double dx = x - kCentre, dy = y - kCentre, dz = z - kCentre;
        return dx * dx + dy * dy + dz * dz < 36.0;
    }
    /// Bright isolated specks in the air (a ghost or a spike): single voxels
    /// and one 2 × 2 × 2 blob, far from the head.
    static bool speck(int x, int y, int z)
    {
        static const int kSingles[][3] = {{2, 2, 2}, {61, 3, 60}, {3, 60, 31}, {60, 60, 2}};
        for (const auto& s : kSingles) {
            if (x == s[0] && y == s[1] && z == s[2]) return true;
        }
        return x >= 4 && x <= 5 && y >= 30 && y <= 31 && z >= 58 && z <= 59;
    }
};

/// The rule on @p grid, its line recorded with the test's properties.
MrBackgroundResult run(FloatGrid& grid, const IndexBox& box)
{
    MrBackgroundResult r = removeMrBackground(grid, box);
    ::testing::Test::RecordProperty("rule", r.rule);
    return r;
}

bool active(const FloatGrid& g, int x, int y, int z) { return g.tree().isValueOn(openvdb::Coord(x, y, z)); }

TEST(MrBackground, SyntheticHeadInRayleighNoise)
{
    std::mt19937 rng(27);
    const IndexBox box = cube(kSize);
    std::vector<float> image(std::size_t(box.voxelCount()));
    const auto at = [](int x, int y, int z) { return std::size_t(x + kSize * (y + kSize * z)); };
    for (int z = 0; z < kSize; ++z) {
        for (int y = 0; y < kSize; ++y) {
            for (int x = 0; x < kSize; ++x) {
                float& v = image[at(x, y, z)];
                if (Head::speck(x, y, z)) {
                    v = 300.0f;
                } else if (Head::ellipsoid(x, y, z) >= 1.0) {
                    v = rician(0.0, kSigma, rng);
                } else {
                    v = rician(Head::ventricle(x, y, z) ? kSigma : kTissue, kSigma, rng);
                }
            }
        }
    }
    auto grid = denseGrid(box, [&](int x, int y, int z) { return image[at(x, y, z)]; });
    const MrBackgroundResult r = run(*grid, box);
    ASSERT_TRUE(r.applied) << r.rule;
    EXPECT_FALSE(r.zeroBackground);
    EXPECT_NEAR(r.noiseFloor / kSigma, 1.0, kSigmaRelTolerance) << r.rule;
    EXPECT_DOUBLE_EQ(r.threshold, mrNoiseMultiple(box.voxelCount()) * r.noiseFloor) << r.rule;
    EXPECT_EQ(r.activeBefore, box.voxelCount());
    EXPECT_GE(r.components, 6) << "the head and the five specks at least";
    EXPECT_GT(r.holesFilled, 0) << r.rule;
    EXPECT_FALSE(r.rule.empty());

    // Every voxel: inside the head (ventricle included) active with its value,
    // outside inactive with the background. With T = √(2 ln N)·σ about one
    // noise voxel of the whole cube is expected above T, and it must also
    // touch the head to stay: the surface is exact (for this seed).
    std::int64_t insideVoxels = 0, wrong = 0;
    for (int z = 0; z < kSize; ++z) {
        for (int y = 0; y < kSize; ++y) {
            for (int x = 0; x < kSize; ++x) {
                const float expected = image[at(x, y, z)];
                const bool inside = Head::ellipsoid(x, y, z) < 1.0;
                insideVoxels += inside;
                const openvdb::Coord ijk(x, y, z);
                if (inside) {
                    wrong += !grid->tree().isValueOn(ijk) || grid->tree().getValue(ijk) != expected;
                } else {
                    wrong += grid->tree().isValueOn(ijk) || grid->tree().getValue(ijk) != kAirIntensity;
                }
            }
        }
    }
    EXPECT_EQ(wrong, 0);
    EXPECT_EQ(r.activeAfter, insideVoxels);
    EXPECT_TRUE(active(*grid, 31, 31, 31)) << "the ventricle is a filled hole";
    EXPECT_FALSE(active(*grid, 2, 2, 2)) << "a speck";
    EXPECT_FALSE(active(*grid, 4, 30, 58)) << "the blob";
}

TEST(MrBackground, ZeroBackgroundIsMaskedAir)
{
    std::mt19937 rng(28);
    const IndexBox box = cube(kSize);
    auto grid = denseGrid(box, [&](int x, int y, int z) {
        if (Head::ellipsoid(x, y, z) >= 1.0) return 0.0f; // the scanner zeroed the air
        return rician(Head::ventricle(x, y, z) ? kSigma : kTissue, kSigma, rng);
    });
    // Constant 8³ blocks of active zeros as active tiles, as a pruned grid holds them.
    openvdb::tools::prune(grid->tree());
    ASSERT_GT(grid->tree().activeTileCount(), 0u);
    const MrBackgroundResult r = run(*grid, box);
    ASSERT_TRUE(r.applied) << r.rule;
    EXPECT_TRUE(r.zeroBackground) << r.rule;
    EXPECT_EQ(r.noiseFloor, 0.0);
    EXPECT_GT(r.threshold, 0.0);
    EXPECT_LE(r.threshold, 1.0) << "the smallest positive value of integer data";
    EXPECT_NE(r.rule.find("zero background"), std::string::npos) << r.rule;
    std::int64_t inside = 0;
    for (int z = 0; z < kSize; ++z) {
        for (int y = 0; y < kSize; ++y) {
            for (int x = 0; x < kSize; ++x) {
                const bool in = Head::ellipsoid(x, y, z) < 1.0;
                inside += in;
                ASSERT_EQ(active(*grid, x, y, z), in) << x << "," << y << "," << z;
            }
        }
    }
    EXPECT_EQ(r.activeAfter, inside);
}

TEST(MrBackground, NoAirRemovesNothing)
{
    std::mt19937 rng(29);
    const IndexBox box = cube(kSize);
    // Tissue to every face, with the dark ventricle (Rician values that look
    // like a little Rayleigh noise, 0.35 % of the voxels): the low end of the
    // histogram below BET's threshold is the flank of the tissue peak.
    auto grid = denseGrid(
        box, [&](int x, int y, int z) { return rician(Head::ventricle(x, y, z) ? kSigma : kTissue, kSigma, rng); });
    const auto before = grid->deepCopy();
    const MrBackgroundResult r = run(*grid, box);
    EXPECT_FALSE(r.applied) << r.rule;
    EXPECT_NE(r.rule.find("no air"), std::string::npos) << r.rule;
    EXPECT_EQ(r.activeAfter, r.activeBefore);
    EXPECT_EQ(r.activeAfter, box.voxelCount());
    EXPECT_EQ(grid->tree().leafCount(), before->tree().leafCount());
    std::int64_t changed = 0;
    for (auto it = before->cbeginValueOn(); it; ++it) changed += grid->tree().getValue(it.getCoord()) != *it;
    EXPECT_EQ(changed, 0);
}

TEST(MrBackground, EnclosedAirOnlyRemovesNothing)
{
    // Tissue to every face around a closed cavity of pure noise (radius 12,
    // 2.8 % of the voxels: a lung in a body cropped by the field of view).
    // The noise is real and σ is found, but nothing below T reaches the
    // border: there is no air around the body to remove.
    std::mt19937 rng(34);
    const IndexBox box = cube(kSize);
    const auto cavity = [](int x, int y, int z) {
        const double dx = x - Head::kCentre, dy = y - Head::kCentre, dz = z - Head::kCentre;
        return dx * dx + dy * dy + dz * dz < 144.0;
    };
    auto grid =
        denseGrid(box, [&](int x, int y, int z) { return rician(cavity(x, y, z) ? 0.0 : kTissue, kSigma, rng); });
    const MrBackgroundResult r = run(*grid, box);
    EXPECT_FALSE(r.applied) << r.rule;
    EXPECT_NEAR(r.noiseFloor / kSigma, 1.0, 3 * kSigmaRelTolerance)
        << "7000 noise voxels: 3 times the tolerance; " << r.rule;
    EXPECT_NE(r.rule.find("reach the volume border"), std::string::npos) << r.rule;
    EXPECT_EQ(r.activeAfter, box.voxelCount());
}

TEST(MrBackground, NoAirWithTissueGradientRemovesNothing)
{
    // Smooth tissue everywhere, from 100 to 500 across the volume (a coil
    // sensitivity ramp): no low peak at all.
    std::mt19937 rng(30);
    const IndexBox box = cube(kSize);
    auto grid = denseGrid(box, [&](int x, int, int) { return rician(100.0 + 400.0 * x / (kSize - 1), kSigma, rng); });
    const MrBackgroundResult r = run(*grid, box);
    EXPECT_FALSE(r.applied) << r.rule;
    EXPECT_EQ(r.activeAfter, box.voxelCount());
}

TEST(MrBackground, NoAirKeepsTilesAsTiles)
{
    // Uniform tissue stored as active tiles: nothing to remove, and the grid
    // keeps its tiles (the rule voxelizes them to look, then prunes).
    initializeOpenVdb();
    const IndexBox box = cube(kSize);
    auto grid = FloatGrid::create(kAirIntensity);
    grid->tree().fill(toCoordBBox(box), float(kTissue), true);
    grid->tree().voxelizeActiveTiles();
    openvdb::tools::prune(grid->tree());
    ASSERT_EQ(grid->tree().leafCount(), 0u);
    const MrBackgroundResult r = run(*grid, box);
    EXPECT_FALSE(r.applied) << r.rule;
    EXPECT_EQ(r.activeAfter, box.voxelCount());
    EXPECT_EQ(grid->tree().leafCount(), 0u);
}

TEST(MrBackground, DarkTissueAtTheBorderIsNotNoise)
{
    // No air: a dark tissue layer 4 voxels thick on every face (Gaussian
    // 30 ± 4, like fat-suppressed skin) around bright tissue. Its low peak is
    // below BET's threshold but has not the Rayleigh shape: removing what lies
    // below 5 "σ" of it would strip the layer.
    std::mt19937 rng(33);
    std::normal_distribution<double> layer(30.0, 4.0);
    const IndexBox box = cube(kSize);
    auto grid = denseGrid(box, [&](int x, int y, int z) {
        const int edge = std::min({x, y, z, kSize - 1 - x, kSize - 1 - y, kSize - 1 - z});
        return edge < 4 ? float(std::round(layer(rng))) : rician(800.0, kSigma, rng);
    });
    const MrBackgroundResult r = run(*grid, box);
    EXPECT_FALSE(r.applied) << r.rule;
    EXPECT_NE(r.rule.find("not Rayleigh"), std::string::npos) << r.rule;
    EXPECT_EQ(r.activeAfter, box.voxelCount());
}

TEST(MrBackground, LittleAirBodyTouchingTheBorders)
{
    // A body that fills the volume but for air in the four corners of every
    // axial slice (a torso cut by the field of view): 12 % air.
    std::mt19937 rng(31);
    const IndexBox box = cube(kSize);
    const auto inBody = [](int x, int y) {
        const double dx = (x - Head::kCentre) / 36.0, dy = (y - Head::kCentre) / 36.0;
        return dx * dx + dy * dy < 1.0;
    };
    auto grid = denseGrid(box, [&](int x, int y, int) { return rician(inBody(x, y) ? kTissue : 0.0, kSigma, rng); });
    const MrBackgroundResult r = run(*grid, box);
    ASSERT_TRUE(r.applied) << r.rule;
    EXPECT_NEAR(r.noiseFloor / kSigma, 1.0, 2 * kSigmaRelTolerance)
        << "fewer noise voxels: twice the tolerance; " << r.rule;
    std::int64_t body = 0, wrong = 0;
    for (int z = 0; z < kSize; ++z) {
        for (int y = 0; y < kSize; ++y) {
            for (int x = 0; x < kSize; ++x) {
                body += inBody(x, y);
                wrong += active(*grid, x, y, z) != inBody(x, y);
            }
        }
    }
    EXPECT_EQ(wrong, 0);
    EXPECT_EQ(r.activeAfter, body);
    EXPECT_LT(double(body), 0.95 * double(box.voxelCount()));
}

TEST(MrBackground, FloatValuesAndAnOffsetBox)
{
    // Unrounded values (a rescaled image) and a box that does not start at 0:
    // the float histogram path and the index arithmetic.
    std::mt19937 rng(32);
    const IndexBox box{voxhap::Vec3i(-21, 5, 100), voxhap::Vec3i(-21 + kSize - 1, 5 + kSize - 1, 100 + kSize - 1)};
    std::normal_distribution<double> noise(0.0, kSigma);
    const auto value = [&](int x, int y, int z) {
        const bool in = Head::ellipsoid(x + 21, y - 5, z - 100) < 1.0;
        return float(std::hypot((in ? kTissue : 0.0) + noise(rng), noise(rng)) * 0.37); // scaled: σ' = 3.7
    };
    auto grid = denseGrid(box, value);
    const MrBackgroundResult r = run(*grid, box);
    ASSERT_TRUE(r.applied) << r.rule;
    EXPECT_NEAR(r.noiseFloor / (0.37 * kSigma), 1.0, kSigmaRelTolerance) << r.rule;
    EXPECT_TRUE(active(*grid, -21 + 31, 5 + 31, 100 + 31));
    EXPECT_FALSE(active(*grid, -21, 5, 100));
    std::int64_t inside = 0;
    for (int z = 0; z < kSize; ++z) {
        for (int y = 0; y < kSize; ++y) {
            for (int x = 0; x < kSize; ++x) inside += Head::ellipsoid(x, y, z) < 1.0;
        }
    }
    EXPECT_EQ(r.activeAfter, inside) << r.rule;
}

TEST(MrBackground, RefusesAGridThatIsNotFloat)
{
    initializeOpenVdb();
    auto labels = LabelGrid::create(0);
    EXPECT_THROW(removeMrBackground(*labels, cube(4)), voxhap::ValueError);
    auto grid = FloatGrid::create(0.0f);
    EXPECT_THROW(removeMrBackground(*grid, IndexBox{}), voxhap::ValueError);
}

/// The rule on a real series loaded with raw intensities; prints its figures.
struct RealFigures {
    MrBackgroundResult result;
    std::int64_t dense = 0;
    double activeFraction = 0, leafFraction = 0, memoryRatio = 0;
    bool centreActive = false;
};

RealFigures runOnSeries(const std::filesystem::path& dir, std::size_t volume = 0)
{
    DicomOptions options;
    options.volume = volume;
    options.normaliseT1Weighted = false;
    options.removeMrBackground = false; // the loader's own call of the rule: off, to run it here
    const Volume v = loadDicom({dir}, options);
    FloatGrid::ConstPtr raw = t1Grid(v);
    if (!raw) raw = intensityGrid(v);
    if (!raw) throw std::runtime_error("no float grid in " + dir.string());
    FloatGrid::Ptr grid = raw->deepCopy();
    const IndexBox& box = v.indexBox();
    RealFigures f;
    f.result = removeMrBackground(*grid, box);
    f.dense = box.voxelCount();
    f.activeFraction = double(grid->activeVoxelCount()) / double(f.dense);
    const voxhap::Vec3i dims = box.dims();
    const double blocks = std::ceil(dims.x() / 8.0) * std::ceil(dims.y() / 8.0) * std::ceil(dims.z() / 8.0);
    f.leafFraction = double(grid->tree().leafCount()) / blocks;
    f.memoryRatio = double(grid->memUsage()) / (4.0 * double(f.dense));
    const voxhap::Vec3i centre = (box.min + box.max) / 2;
    f.centreActive = grid->tree().isValueOn(toCoord(centre));
    std::printf(
        "[ figures  ] %s%s: %.1f %% active, %.3f of the leaves, memory %.3f of dense float, %.3f s\n[ rule     ] %s\n",
        dir.filename().string().c_str(), volume ? (" volume " + std::to_string(volume)).c_str() : "",
        100 * f.activeFraction, f.leafFraction, f.memoryRatio, f.result.seconds, f.result.rule.c_str());
    return f;
}

TEST(MrBackground, SharedMprageMeetsTheTargets)
{
    VOXHAP_REQUIRE_DIR(voxhap::test::mprageDir());
    const RealFigures f = runOnSeries(voxhap::test::mprageDir());
    ASSERT_TRUE(f.result.applied) << f.result.rule;
    EXPECT_FALSE(f.result.zeroBackground);
    // Issue 27 item 7's targets.
    EXPECT_LE(f.activeFraction, 0.50);
    EXPECT_LE(f.memoryRatio, 0.60);
    EXPECT_TRUE(f.centreActive) << "the head's interior";
    // The clarification measured 43–47 % active for thresholds 20–30 on these
    // raw values: the head itself is about that, so far fewer would mean tissue
    // was cut, and a threshold outside that range was not validated.
    EXPECT_GE(f.activeFraction, 0.40);
    EXPECT_GE(f.result.threshold, 20.0);
    EXPECT_LE(f.result.threshold, 30.0);
    EXPECT_LT(f.result.threshold, f.result.betThreshold) << "below BET's background/object threshold";
    EXPECT_GT(f.result.holesFilled, 0);
}

TEST(MrBackground, SharedFlash2dKeepsTheHead)
{
    VOXHAP_REQUIRE_DIR(voxhap::test::flash2dDir());
    const RealFigures f = runOnSeries(voxhap::test::flash2dDir());
    ASSERT_TRUE(f.result.applied) << f.result.rule;
    EXPECT_FALSE(f.result.zeroBackground);
    EXPECT_TRUE(f.centreActive) << "the head's interior";
    EXPECT_LT(f.result.threshold, f.result.betThreshold) << "below BET's background/object threshold";
    // A sagittal head section (about 150 × 190 mm, plus the neck) in a
    // 260 × 260 mm field of view covers 40–50 % of each slice, less in the
    // lateral slices: 30–55 % of the voxels (measured 41 %).
    EXPECT_GE(f.activeFraction, 0.30);
    EXPECT_LE(f.activeFraction, 0.55);
    // Leaves (8³ blocks) occupied, as for the MPRAGE's memory target; the
    // memory ratio itself is inflated here by the 35 slices, 5 leaves deep.
    EXPECT_LE(f.leafFraction, 0.60);
}

TEST(MrBackground, SharedDiffusionVolumesShareOneNoiseFloor)
{
    // The b = 0 and a b = 1000 volume of one diffusion series: the same
    // receiver noise under very different tissue contrast. The noise floor
    // must agree (an independent check of the estimator) and both heads stay.
    VOXHAP_REQUIRE_DIR(voxhap::test::dwiMosaicDir());
    const RealFigures b0 = runOnSeries(voxhap::test::dwiMosaicDir(), 1);
    const RealFigures b1000 = runOnSeries(voxhap::test::dwiMosaicDir(), 2);
    ASSERT_TRUE(b0.result.applied) << b0.result.rule;
    ASSERT_TRUE(b1000.result.applied) << b1000.result.rule;
    EXPECT_NEAR(b1000.result.noiseFloor / b0.result.noiseFloor, 1.0, kSigmaRelTolerance);
    EXPECT_TRUE(b0.centreActive);
    EXPECT_TRUE(b1000.centreActive);
    for (const RealFigures* f : {&b0, &b1000}) {
        EXPECT_GE(f->activeFraction, 0.25);
        EXPECT_LE(f->activeFraction, 0.60);
    }
}

} // namespace mrbackground_test
