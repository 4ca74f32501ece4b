// SPDX-License-Identifier: Apache-2.0
/// @file TestSegmentationMemory.cpp
/// @brief The parallel and slab-wise building blocks against plain serial
/// references (random masks, several threads), and the memory cap of
/// segmentation: refused in one line below the estimate, done above it, and
/// the child process's peak within the estimate.

#include "common/CliRunner.h"
#include "common/Prerequisites.h"
#include "core/Errors.h"
#include "phantoms/Phantoms.h"
#include "segmentation/DistanceField.h"
#include "segmentation/Segmentation.h"
#include "segmentation/lattice/Components.h"
#include "segmentation/lattice/DistanceTransform.h"
#include "segmentation/lattice/Morphology.h"
#include "volume/Grids.h"
#include "volume/VolumeFile.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <sys/resource.h>

#include <deque>
#include <random>

namespace voxhap::segmentation {
namespace {

Lattice smallLattice(Vec3i dims, Vec3d spacing, int sliceAxis = 2)
{
    Lattice lat;
    lat.dims = dims;
    lat.spacing = spacing;
    lat.sliceAxis = sliceAxis;
    return lat;
}

/// A random mask of blobs: dense enough that components touch across slabs.
Mask randomMask(const Lattice& lat, double fill, unsigned seed)
{
    std::mt19937 rng(seed);
    std::bernoulli_distribution on(fill);
    Mask m(lat.size());
    for (auto& x : m) x = on(rng) ? 1 : 0;
    return m;
}

/// The serial flood fill the run-based labelling replaced: components numbered
/// in the order of their first voxel in memory.
std::vector<std::int32_t> floodFill(const Lattice& lat, const Mask& m, Span span)
{
    std::vector<std::int32_t> id(m.size(), 0);
    std::int32_t next = 0;
    const auto strides = lat.strides();
    for (std::size_t seed = 0; seed < m.size(); ++seed) {
        if (!m[seed] || id[seed]) continue;
        id[seed] = ++next;
        std::vector<std::size_t> stack{seed};
        while (!stack.empty()) {
            const std::size_t n = stack.back();
            stack.pop_back();
            const Vec3i p = lat.position(n);
            for (int a = 0; a < 3; ++a) {
                if (span == Span::Slice && a == lat.sliceAxis) continue;
                for (const int d : {-1, 1}) {
                    if (p[a] + d < 0 || p[a] + d >= lat.dims[a]) continue;
                    const std::size_t q = d < 0 ? n - strides[std::size_t(a)] : n + strides[std::size_t(a)];
                    if (m[q] && !id[q]) {
                        id[q] = next;
                        stack.push_back(q);
                    }
                }
            }
        }
    }
    return id;
}

/// The serial breadth-first growth the parallel steps must reproduce.
void growSerial(const Lattice& lat, std::vector<std::int32_t>& ids, const Mask& within)
{
    std::deque<std::size_t> front;
    for (std::size_t n = 0; n < ids.size(); ++n)
        if (ids[n]) front.push_back(n);
    const auto strides = lat.strides();
    while (!front.empty()) {
        const std::size_t n = front.front();
        front.pop_front();
        const Vec3i p = lat.position(n);
        for (int a = 0; a < 3; ++a) {
            for (const int d : {-1, 1}) {
                if (p[a] + d < 0 || p[a] + d >= lat.dims[a]) continue;
                const std::size_t q = d < 0 ? n - strides[std::size_t(a)] : n + strides[std::size_t(a)];
                if (within[q] && !ids[q]) {
                    ids[q] = ids[n];
                    front.push_back(q);
                }
            }
        }
    }
}

TEST(SegmentationParallel, ComponentsEqualTheSerialFloodFillForEverySpan)
{
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 4);
    for (int sliceAxis = 0; sliceAxis < 3; ++sliceAxis) {
        const Lattice lat = smallLattice({37, 29, 41}, {1, 1, 2}, sliceAxis);
        const Mask m = randomMask(lat, 0.45, 7u + unsigned(sliceAxis));
        for (const Span span : {Span::Volume, Span::Slice}) {
            const Components cc = connectedComponents(lat, m, span);
            const std::vector<std::int32_t> ref = floodFill(lat, m, span);
            EXPECT_EQ(cc.id, ref) << "slice axis " << sliceAxis << ", span " << int(span);
            const auto count = *std::max_element(ref.begin(), ref.end());
            ASSERT_EQ(cc.list.size(), std::size_t(count));
            std::int64_t voxels = 0;
            for (const Component& c : cc.list) voxels += c.voxels;
            EXPECT_EQ(voxels, std::count(m.begin(), m.end(), 1));
        }
    }
}

TEST(SegmentationParallel, RegionGrowingEqualsTheSerialBreadthFirstPass)
{
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 4);
    const Lattice lat = smallLattice({64, 48, 40}, {1, 1, 1});
    const Mask within = randomMask(lat, 0.7, 3);
    // Many seeds with many labels: ties between fronts arriving together are common.
    std::vector<std::int32_t> seeds(lat.size(), 0);
    std::mt19937 rng(5);
    std::uniform_int_distribution<std::size_t> at(0, lat.size() - 1);
    for (int s = 1; s <= 300; ++s) seeds[at(rng)] = s;
    std::vector<std::int32_t> parallel = seeds, serial = seeds;
    growRegions(lat, parallel, within);
    growSerial(lat, serial, within);
    EXPECT_EQ(parallel, serial);
    EXPECT_GT(std::count_if(serial.begin(), serial.end(), [](std::int32_t x) { return x != 0; }), 300);
}

TEST(SegmentationParallel, SlabErosionAndDilationEqualTheWholeLatticeTransform)
{
    const Lattice lat = smallLattice({40, 36, 30}, {0.8, 0.8, 1.3});
    const Mask m = randomMask(lat, 0.8, 9);
    for (const double r : {0.9, 2.0, 3.5}) {
        const float r2 = float(r * r);
        const std::vector<float> toOut = squaredDistance(lat, m, Span::Volume, /*complement=*/true);
        const std::vector<float> toIn = squaredDistance(lat, m, Span::Volume);
        const Mask er = erode(lat, m, r, Span::Volume), di = dilate(lat, m, r, Span::Volume);
        for (std::size_t i = 0; i < m.size(); ++i) {
            ASSERT_EQ(er[i], (m[i] && toOut[i] > r2) ? 1 : 0) << "erosion by " << r << " at " << i;
            ASSERT_EQ(di[i], toIn[i] <= r2 ? 1 : 0) << "dilation by " << r << " at " << i;
        }
    }
}

TEST(SegmentationParallel, DistanceFieldOnItsBoxEqualsTheWholeLattice)
{
    // A structure in the middle of a larger lattice: the field computed on its
    // widened box must read like the one over the whole lattice, voxel for voxel.
    const Lattice lat = smallLattice({60, 50, 30}, {1.0, 1.0, 2.5});
    std::vector<std::int32_t> labels(lat.size(), 0);
    for (int k = 12; k < 18; ++k)
        for (int j = 20; j < 27; ++j)
            for (int i = 25; i < 33; ++i) labels[lat.index(i, j, k)] = 7;
    const double band = 6.0;
    const auto field = openvdb::gridPtrCast<volume::FloatGrid>(signedDistanceField(lat, labels, 7, band));
    const Lattice box = distanceFieldBox(lat, labels, 7, band);
    EXPECT_LT(box.size(), lat.size());
    Mask inside(lat.size());
    for (std::size_t i = 0; i < lat.size(); ++i) inside[i] = labels[i] == 7;
    const std::vector<float> toIn = squaredDistance(lat, inside, Span::Volume);
    const std::vector<float> toOut = squaredDistance(lat, inside, Span::Volume, true);
    const auto acc = field->getConstAccessor();
    for (std::size_t n = 0; n < lat.size(); ++n) {
        const Vec3i p = lat.position(n);
        const double d = inside[n] ? -(std::sqrt(double(toOut[n])) - 0.5) : std::sqrt(double(toIn[n])) - 0.5;
        const float expected = std::clamp(float(d), -float(band), float(band));
        ASSERT_EQ(acc.getValue(openvdb::Coord(p.x(), p.y(), p.z())), expected) << p.transpose();
    }
}

TEST(SegmentationParallel, StreamedSmoothingEqualsAPlainSeparableFilter)
{
    const Lattice lat = smallLattice({23, 19, 17}, {0.7, 0.9, 0.6});
    std::vector<float> values(lat.size());
    std::mt19937 rng(1);
    std::normal_distribution<float> noise(0, 100);
    for (float& x : values) x = noise(rng);
    const double sigma = 1.0;
    // The reference: three whole-lattice passes, each rounded to float.
    std::vector<float> cur = values, next(values.size());
    for (int axis = 0; axis < 3; ++axis) {
        const double s = sigma / lat.spacing[axis];
        const int radius = int(std::ceil(3.0 * s));
        std::vector<double> w(std::size_t(2 * radius + 1));
        double sum = 0;
        for (int t = -radius; t <= radius; ++t) sum += w[std::size_t(t + radius)] = std::exp(-0.5 * t * t / (s * s));
        for (std::size_t n = 0; n < cur.size(); ++n) {
            const Vec3i p = lat.position(n);
            double acc = 0;
            for (int t = -radius; t <= radius; ++t) {
                Vec3i q = p;
                q[axis] = std::clamp(p[axis] + t, 0, lat.dims[axis] - 1);
                acc += w[std::size_t(t + radius)] / sum * cur[lat.index(q.x(), q.y(), q.z())];
            }
            next[n] = float(acc);
        }
        std::swap(cur, next);
    }
    const std::vector<float> smooth = gaussianSmooth(lat, values, sigma);
    for (std::size_t n = 0; n < cur.size(); ++n) ASSERT_NEAR(smooth[n], cur[n], 1e-3f * (1.0f + std::abs(cur[n]))) << n;
}

/// A small CT-like phantom (no labels): what segment() labels from HU.
volume::Volume ctPhantom()
{
    const auto& table = volume::TissueTable::builtin();
    volume::TorsoParams p;
    p.grid.spacing = Vec3d(2.0, 2.0, 3.0);
    volume::Volume v = volume::makePhantom(volume::torsoModel(p, table), p.grid, table);
    v.removeGrid(volume::Channel::Label);
    v.removeGrid(volume::Channel::T1);
    return v;
}

std::uint64_t inputBytes(const volume::Volume& v) { return volume::huGrid(v)->memUsage(); }

TEST(SegmentationMemory, ACapBelowTheEstimateIsRefusedBeforeAnyLabel)
{
    volume::Volume v = ctPhantom();
    const std::uint64_t estimate = workingBytes(v);
    ASSERT_GT(estimate, 0u);
    SegmentOptions o;
    o.memoryCapBytes = inputBytes(v) + estimate / 2;
    try {
        segment(v, volume::TissueTable::builtin(), o);
        FAIL() << "a cap below the estimate was accepted";
    } catch (const ValueError& e) {
        const std::string what = e.what();
        EXPECT_EQ(what.find('\n'), std::string::npos) << what;
        EXPECT_NE(
            what.find("over the memory cap of " + std::to_string(std::llround(double(o.memoryCapBytes) / (1 << 20)))),
            std::string::npos)
            << what;
        EXPECT_NE(what.find("needs about " + std::to_string(std::llround(double(estimate) / (1 << 20))) + " MiB"),
            std::string::npos)
            << what;
    }
    EXPECT_FALSE(v.has(volume::Channel::Label)) << "the refusal came after work had started";
}

TEST(SegmentationMemory, ACapAboveTheEstimateSegments)
{
    volume::Volume v = ctPhantom();
    SegmentOptions o;
    // The second check (distance fields) may raise the estimate: leave room for it.
    o.memoryCapBytes = inputBytes(v) + 2 * workingBytes(v);
    const SegmentReport r = segment(v, volume::TissueTable::builtin(), o);
    EXPECT_TRUE(v.has(volume::Channel::Label));
    EXPECT_FALSE(r.distanceFields.empty());
    EXPECT_LE(r.inputBytes + r.workingBytes, o.memoryCapBytes);
}

class SegmentationMemoryCli : public test::CliTest { };

TEST_F(SegmentationMemoryCli, RefusalIsOneLineWithNoOutputAndThePeakStaysWithinTheEstimate)
{
    VOXHAP_REQUIRE(std::filesystem::exists(VOXHAP_BINARY_DIR "/bin/voxhap"),
        "the voxhap program (a build with VOXHAP_WITH_RENDER and VOXHAP_WITH_IGTL)");
    // A CT phantom as a file, as a user would give it.
    volume::saveVolume(ctPhantom(), mDir / "ct.vdb");
    // The process's own floor (its libraries), measured the same way as the peak below.
    ASSERT_EQ(run("--version").exitCode, 0);
    rusage floor{};
    getrusage(RUSAGE_CHILDREN, &floor);

    const test::CliResult ok = run("segment ct.vdb --out seg.vdb --json");
    ASSERT_EQ(ok.exitCode, 0) << ok.err;
    rusage peak{};
    getrusage(RUSAGE_CHILDREN, &peak); // the largest child so far: this segment
    const auto j = nlohmann::json::parse(ok.out);
    const double inputMib = j["memory_mib"]["input"].get<double>();
    const double estimateMib = j["memory_mib"]["working_estimate"].get<double>();
    const double peakAboveFloorMib = double(peak.ru_maxrss - floor.ru_maxrss) / 1024.0;
    EXPECT_LE(peakAboveFloorMib, inputMib + estimateMib)
        << "peak " << peak.ru_maxrss / 1024.0 << " MiB, floor " << floor.ru_maxrss / 1024.0 << " MiB";

    // A cap below what the volume and the work need: refused in one line naming
    // both figures, exit 1, nothing written.
    const long cap = std::max(1L, long(std::floor(inputMib + estimateMib / 2)));
    const test::CliResult refused =
        run("segment ct.vdb --out capped.vdb --export capped.nrrd --memory-cap " + std::to_string(cap));
    test::expectError(refused, 1, "over the memory cap of " + std::to_string(cap) + " MiB");
    EXPECT_NE(refused.err.find("needs about"), std::string::npos) << refused.err;
    EXPECT_FALSE(std::filesystem::exists(mDir / "capped.vdb"));
    EXPECT_FALSE(std::filesystem::exists(mDir / "capped.nrrd"));

    // A cap above it: done.
    const long roomy = long(std::ceil(2 * (inputMib + estimateMib))) + 16;
    EXPECT_EQ(run("segment ct.vdb --out roomy.vdb --memory-cap " + std::to_string(roomy)).exitCode, 0);
    EXPECT_TRUE(std::filesystem::exists(mDir / "roomy.vdb"));
}

} // namespace
} // namespace voxhap::segmentation
