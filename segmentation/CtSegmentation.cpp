// SPDX-License-Identifier: Apache-2.0
/// @file CtSegmentation.cpp
/// @brief The CT rules of CtSegmentation.h. Thresholds cite physics.md §5.2 or
/// the tissue table; the size and shape rules are [chosen] and were tuned on
/// the contrast-enhanced abdominal CT of the test data, then checked on the
/// torso phantom.

#include "segmentation/CtSegmentation.h"

#include "core/Errors.h"
#include "segmentation/detail/VoxelLoops.h"
#include "segmentation/lattice/Components.h"
#include "segmentation/lattice/DistanceTransform.h"
#include "segmentation/lattice/Morphology.h"
#include "volume/Grids.h"

#include <openvdb/tools/Dense.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <utility>

namespace voxhap::segmentation {

namespace {

// Step 1, body. −500 HU is halfway between air (−1000) and fat (about −100,
// physics.md §5.2): partial-volume voxels on the skin split evenly.
constexpr float kBodyHu = -500.0f;
// An in-plane opening of 5 mm cuts the patient off the table, its pad and the
// side rails, which touch the body through contacts thinner than 10 mm [chosen].
constexpr double kBodyOpeningMm = 5.0;
// Slice islands smaller than this are rail or cable fragments the opening
// re-attached, not body [chosen]: the smallest body cross-section (an arm at the
// edge of the field of view) is tens of cm².
constexpr double kMinIslandMm2 = 400.0;
// Smoothing before thresholds: 1 mm takes the CT's quantum noise (σ of 10 to 30 HU
// in soft tissue) down enough for the tissue windows, and moves a boundary by well
// under a voxel [chosen].
constexpr double kSmoothingMm = 1.0;

// Step 2, lung: gas is below −400 HU (lung −550 to −950, physics.md §5.2).
constexpr float kGasHu = -400.0f;
constexpr double kLungMinMl = 50.0;             // bowel gas pockets are smaller here; lung bases larger [chosen]
constexpr float kPureAirHu = -950.0f;           // parenchyma rarely reaches it (§5.2: down to −950)
constexpr double kLungMaxPureAirFraction = 0.2; // bowel gas: 25–40 % of its voxels below −950 HU [chosen]

// Step 3, enhanced structures. 120 HU, after smoothing, sits between muscle
// (40–60 HU, §5.2) and enhanced kidney cortex (130–250 HU in the test CT);
// bone itself is ≥ 150 HU (§5.2 "segment bone by a threshold of about 150 HU").
constexpr float kEnhancedHu = 120.0f;
constexpr float kBoneHu = 150.0f;
// Eroding 2.5 mm separates the vertebrae from the aorta and the kidneys, which
// touch them through fat planes a few millimetres thick [chosen].
constexpr double kCoreErosionMm = 2.5;
constexpr float kDenseBoneHu = 600.0f;      // cortex; vessels and organs stay below (§5.2 aorta ≤ 450)
constexpr double kBoneDenseFraction = 0.05; // vertebrae 15 %, ribs 3–18 % in the test CT; 0 for organs [chosen]
// Aorta: a tube along the body [chosen]; diameter 14–39 mm.
constexpr double kAortaMinLengthMm = 60.0;
constexpr double kAortaMinAreaMm2 = 150.0, kAortaMaxAreaMm2 = 1200.0;
// The aorta lies on the front of the spine; the sternum and costal cartilage,
// also long and midline, are 100 mm and more anterior [chosen].
constexpr double kAortaMaxAnteriorMm = 60.0;
// Kidney: 40–400 ml, median 180–300 HU in the nephrographic/arterial phase,
// its centre 30–130 mm lateral of the spine [chosen].
constexpr double kKidneyMinMl = 40.0, kKidneyMaxMl = 400.0;
// The lower bound keeps the spleen (median 160 HU in the test CT, the kidneys 210) out.
constexpr double kKidneyMinHu = 180.0, kKidneyMaxHu = 300.0;
constexpr double kKidneyMinLateralMm = 30.0, kKidneyMaxLateralMm = 130.0;
// ... and retroperitoneal: within 70 mm of the spine front to back, which keeps
// the heart (as bright, about 100 mm anterior) out [chosen].
constexpr double kKidneyMaxAnteriorMm = 70.0;
// Holes in bone smaller than this are marrow fat or noise, not anatomy [chosen].
constexpr double kBoneHoleMaxMm2 = 50.0;

// Step 6, spinal canal: a 7 mm closing bridges the gaps of up to about 10 mm between
// pedicles and laminae (a closing by more fills the canal itself, whose radius
// is about 9 mm); the canal's cross-section is 1–4 cm² in adults [chosen];
// levels without a bony ring (discs, vertebral bodies below the pedicles) are
// bridged up to 30 mm along the spine.
constexpr double kCanalClosingMm = 7.0;
constexpr double kCanalMinAreaMm2 = 50.0, kCanalMaxAreaMm2 = 500.0;
constexpr double kCanalBridgeMm = 30.0;
constexpr double kCanalMinLengthMm = 30.0;

using detail::forEachVoxel;
using detail::maskWhere;

double sliceAreaMm2(const Lattice& lat)
{
    const auto [a0, a1] = lat.planeAxes();
    return lat.spacing[a0] * lat.spacing[a1];
}

} // namespace

/// Keep, per slice, the in-plane components of @p m whose area is within [minMm2, maxMm2].
Mask filterSliceIslands(const Lattice& lat, const Mask& m, double minMm2, double maxMm2)
{
    const ComponentRuns cc = componentRuns(lat, m, Span::Slice);
    const double area = sliceAreaMm2(lat);
    std::vector<std::uint8_t> keep(cc.list.size() + 1, 0);
    for (std::size_t c = 0; c < cc.list.size(); ++c) {
        const double a = double(cc.list[c].voxels) * area;
        keep[c + 1] = (a >= minMm2 && a <= maxMm2) ? 1 : 0;
    }
    return cc.mask(lat, keep);
}

namespace {

/// Per-region figures for the classification of step 3.
struct RegionStats {
    std::int64_t voxels = 0, dense = 0;
    // Lattice positions summed in integers: exact in any order, so the sums are
    // the same however the voxels are split between threads.
    std::array<std::int64_t, 3> sum{};
    double centreX = 0, centreY = 0; // world x (patient left +) and y (posterior +) of the mean voxel [mm]
    int sliceMin = 1 << 30, sliceMax = -1;
    std::array<std::int64_t, 128> histogram{}; // 25 HU bins from −400 HU
    double ml(const Lattice& lat) const { return double(voxels) * lat.voxelMl(); }
    double lengthMm(const Lattice& lat) const { return (sliceMax - sliceMin + 1) * lat.spacing[lat.sliceAxis]; }
    double meanAreaMm2(const Lattice& lat) const { return ml(lat) * 1e3 / lengthMm(lat); }
    double medianHu() const
    {
        std::int64_t half = (voxels + 1) / 2, seen = 0;
        for (std::size_t b = 0; b < histogram.size(); ++b) {
            seen += histogram[b];
            if (seen >= half) return -400.0 + 25.0 * (double(b) + 0.5);
        }
        return -400.0 + 25.0 * double(histogram.size());
    }
};

std::vector<RegionStats> regionStats(const volume::Volume& v, const Lattice& lat,
    const std::vector<std::int32_t>& region, int regions, const std::vector<float>& hu)
{
    tbb::enumerable_thread_specific<std::vector<RegionStats>> partial(
        [&] { return std::vector<RegionStats>(std::size_t(regions) + 1); });
    const int nx = lat.dims.x(), ny = lat.dims.y();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, std::size_t(ny) * std::size_t(lat.dims.z()), 64),
        [&](const tbb::blocked_range<std::size_t>& rows) {
            std::vector<RegionStats>& s = partial.local();
            for (std::size_t row = rows.begin(); row != rows.end(); ++row) {
                const Vec3i p0(0, int(row % std::size_t(ny)), int(row / std::size_t(ny)));
                for (int i = 0; i < nx; ++i) {
                    const std::size_t n = row * std::size_t(nx) + std::size_t(i);
                    const auto r = std::size_t(region[n]);
                    if (!r) continue;
                    RegionStats& st = s[r];
                    const Vec3i p(i, p0.y(), p0.z());
                    ++st.voxels;
                    st.dense += hu[n] >= kDenseBoneHu;
                    for (int a = 0; a < 3; ++a) st.sum[std::size_t(a)] += p[a];
                    st.sliceMin = std::min(st.sliceMin, p[lat.sliceAxis]);
                    st.sliceMax = std::max(st.sliceMax, p[lat.sliceAxis]);
                    const int bin =
                        std::clamp(int(std::floor((hu[n] + 400.0f) / 25.0f)), 0, int(st.histogram.size()) - 1);
                    ++st.histogram[std::size_t(bin)];
                }
            }
        });
    std::vector<RegionStats> s(std::size_t(regions) + 1);
    for (const auto& part : partial) {
        for (std::size_t r = 0; r < s.size(); ++r) {
            RegionStats& st = s[r];
            const RegionStats& q = part[r];
            st.voxels += q.voxels;
            st.dense += q.dense;
            for (std::size_t a = 0; a < 3; ++a) st.sum[a] += q.sum[a];
            st.sliceMin = std::min(st.sliceMin, q.sliceMin);
            st.sliceMax = std::max(st.sliceMax, q.sliceMax);
            for (std::size_t b = 0; b < st.histogram.size(); ++b) st.histogram[b] += q.histogram[b];
        }
    }
    // The world map is affine: the mean of the voxels' positions is the position of their mean.
    for (RegionStats& st : s) {
        if (!st.voxels) continue;
        const Vec3d mean(double(st.sum[0]) / double(st.voxels), double(st.sum[1]) / double(st.voxels),
            double(st.sum[2]) / double(st.voxels));
        const Vec3d w = v.indexToWorld(lat.origin.cast<double>() + mean);
        st.centreX = w.x();
        st.centreY = w.y();
    }
    return s;
}

/// Fill runs of non-@p m voxels along the slice axis shorter than @p gapMm that
/// lie between two voxels of @p m, where @p allowed.
void bridgeAlongSliceAxis(const Lattice& lat, Mask& m, const Mask& allowed, double gapMm)
{
    const auto strides = lat.strides();
    const auto [a0, a1] = lat.planeAxes();
    const int n = lat.dims[lat.sliceAxis];
    const std::size_t step = strides[std::size_t(lat.sliceAxis)];
    const int maxGap = int(std::floor(gapMm / lat.spacing[lat.sliceAxis]));
    tbb::parallel_for(0, lat.dims[a1], [&](int w) {
        for (int u = 0; u < lat.dims[a0]; ++u) {
            const std::size_t base =
                std::size_t(u) * strides[std::size_t(a0)] + std::size_t(w) * strides[std::size_t(a1)];
            int last = -1;
            for (int q = 0; q < n; ++q) {
                if (!m[base + std::size_t(q) * step]) continue;
                if (last >= 0 && q - last - 1 > 0 && q - last - 1 <= maxGap) {
                    bool ok = true;
                    for (int t = last + 1; t < q && ok; ++t) ok = allowed[base + std::size_t(t) * step] != 0;
                    for (int t = last + 1; t < q && ok; ++t) m[base + std::size_t(t) * step] = 1;
                }
                last = q;
            }
        }
    });
}

} // namespace

Mask ctBodyMask(const Lattice& lat, const std::vector<float>& smoothedHu)
{
    return bodyMask(lat, maskWhere(lat.size(), [&](std::size_t i) { return smoothedHu[i] >= kBodyHu; }));
}

Mask bodyMask(const Lattice& lat, const Mask& dense)
{
    const Mask core = largestComponent(lat, erode(lat, dense, kBodyOpeningMm, Span::Slice));
    const auto [a0, a1] = lat.planeAxes();
    // Grow back one voxel further than the erosion so that the surface is restored exactly.
    const double back = kBodyOpeningMm + std::max(lat.spacing[a0], lat.spacing[a1]);
    Mask body = maskAnd(dilate(lat, core, back, Span::Slice), dense);
    body = filterSliceIslands(lat, body, kMinIslandMm2, 1e300);
    fillHolesPerSlice(lat, body);
    return body;
}

void markSkin(
    const Lattice& lat, const Mask& body, double thicknessMm, std::int32_t skinId, std::vector<std::int32_t>& labels)
{
    // A voxel centre at depth d below the surface lies d + h/2 from the nearest
    // outside centre on average (the surface passes between the two centres).
    const auto [a0, a1] = lat.planeAxes();
    const double reach = thicknessMm + 0.5 * std::min(lat.spacing[a0], lat.spacing[a1]);
    const Mask shell = innerShell(lat, body, reach);
    forEachVoxel(body.size(), [&](std::size_t i) {
        if (shell[i]) labels[i] = skinId;
    });
}

namespace {

// Bits of the smoothed HU's class per voxel: the rules compare the smoothed
// values with these thresholds only, so a byte replaces a float array.
constexpr std::uint8_t kSmoothBody = 1;     // ≥ kBodyHu
constexpr std::uint8_t kSmoothGas = 2;      // < kGasHu
constexpr std::uint8_t kSmoothBelowFat = 4; // < the table's fat maximum
constexpr std::uint8_t kSmoothEnhanced = 8; // ≥ kEnhancedHu

openvdb::CoordBBox latticeBox(const Lattice& lat)
{
    return {volume::toCoord(lat.origin), volume::toCoord(lat.origin + lat.dims - Vec3i::Ones())};
}

/// The k planes [k0, k1) of @p lat read from @p grid into @p out (i fastest).
void readPlanes(const Lattice& lat, const volume::FloatGrid& grid, int k0, int k1, float* out)
{
    openvdb::CoordBBox box = latticeBox(lat);
    box.min().z() = lat.origin.z() + k0;
    box.max().z() = lat.origin.z() + k1 - 1;
    openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> dense(box, out);
    openvdb::tools::copyToDense(grid, dense, /*serial=*/true); // called from parallel tasks
}

/// The sub-lattice @p crop of @p lat: a copy of the elements of @p full inside it.
template <class T> std::vector<T> cropArray(const Lattice& lat, const Lattice& crop, const std::vector<T>& full)
{
    std::vector<T> out(crop.size());
    const Vec3i off = crop.origin - lat.origin;
    tbb::parallel_for(0, crop.dims.z(), [&](int k) {
        for (int j = 0; j < crop.dims.y(); ++j) {
            const std::size_t src = lat.index(off.x(), off.y() + j, off.z() + k);
            std::copy_n(
                full.begin() + std::ptrdiff_t(src), crop.dims.x(), out.begin() + std::ptrdiff_t(crop.index(0, j, k)));
        }
    });
    return out;
}

/// The body's box widened in-plane by @p marginMm (and two voxels), clamped to
/// @p lat; the slice axis stays whole. Every rule after the body mask works on
/// voxels of the body or within the canal closing of them, and a margin of
/// voxels outside the body around them leaves their distances, components and
/// holes as on the whole lattice: the nearest voxel outside a box lies no
/// nearer than the box's own outer layer.
Lattice bodyBox(const Lattice& lat, const Mask& body, double marginMm)
{
    Vec3i lo = lat.dims, hi = -Vec3i::Ones();
    const int nx = lat.dims.x(), ny = lat.dims.y();
    struct Box {
        Vec3i lo, hi;
    };
    tbb::enumerable_thread_specific<Box> boxes([&] { return Box{lo, hi}; });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, std::size_t(ny) * std::size_t(lat.dims.z()), 64),
        [&](const tbb::blocked_range<std::size_t>& rows) {
            Box& b = boxes.local();
            for (std::size_t row = rows.begin(); row != rows.end(); ++row) {
                const std::uint8_t* p = body.data() + row * std::size_t(nx);
                int first = -1, last = -1;
                for (int i = 0; i < nx; ++i) {
                    if (!p[i]) continue;
                    if (first < 0) first = i;
                    last = i;
                }
                if (first < 0) continue;
                const Vec3i a(first, int(row % std::size_t(ny)), int(row / std::size_t(ny)));
                const Vec3i z(last, a.y(), a.z());
                b.lo = b.lo.cwiseMin(a);
                b.hi = b.hi.cwiseMax(z);
            }
        });
    for (const Box& b : boxes) {
        lo = lo.cwiseMin(b.lo);
        hi = hi.cwiseMax(b.hi);
    }
    Lattice crop = lat;
    if ((hi.array() < lo.array()).any()) return crop; // no body: nothing to gain
    for (const int a : lat.planeAxes()) {
        const int m = int(std::ceil(marginMm / lat.spacing[a])) + 2;
        const int a0 = std::max(0, lo[a] - m), a1 = std::min(lat.dims[a] - 1, hi[a] + m);
        crop.origin[a] = lat.origin[a] + a0;
        crop.dims[a] = a1 - a0 + 1;
    }
    return crop;
}

/// The tissue ids the CT rules write, and the thresholds they take from the table.
struct CtTissues {
    std::int32_t skin = 0, fat = 0, muscle = 0, lung = 0, kidney = 0, aorta = 0, cortical = 0, cancellous = 0, soft = 0,
                 canal = 0;
    float corticalHu = 0; // 700 HU
    float fatMaxHu = 0;   // −30 HU
    double skinMm = 0;
};

CtTissues ctTissues(const volume::TissueTable& table)
{
    const auto id = [&](const char* name) { return std::int32_t(table.at(name).id); };
    CtTissues t;
    t.skin = id("skin"), t.fat = id("fat"), t.muscle = id("muscle"), t.lung = id("lung");
    t.kidney = id("kidney"), t.aorta = id("aorta"), t.cortical = id("cortical_bone");
    t.cancellous = id("cancellous_bone"), t.soft = id("soft_tissue"), t.canal = id("spinal_cord");
    t.corticalHu = float(table.at("cortical_bone").huMin);
    t.fatMaxHu = float(table.at("fat").huMax);
    t.skinMm = table.at("skin").thickness ? table.at("skin").thickness->value : 2.0;
    return t;
}

/// Step 1 on the whole box: smoothing streams k planes from the sparse grid
/// into one class byte per voxel (the kSmooth bits).
std::vector<std::uint8_t> smoothedClasses(const Lattice& full, const volume::FloatGrid& huGrid, float fatMaxHu)
{
    std::vector<std::uint8_t> smoothClass(full.size());
    const std::size_t plane = std::size_t(full.dims.x()) * std::size_t(full.dims.y());
    gaussianSmoothPlanes(
        full, kSmoothingMm, [&](int k0, int k1, float* buf) { readPlanes(full, huGrid, k0, k1, buf); },
        [&](int k, const float* s) {
            std::uint8_t* c = smoothClass.data() + plane * std::size_t(k);
            for (std::size_t n = 0; n < plane; ++n) {
                c[n] = std::uint8_t((s[n] >= kBodyHu ? kSmoothBody : 0) | (s[n] < kGasHu ? kSmoothGas : 0) |
                    (s[n] < fatMaxHu ? kSmoothBelowFat : 0) | (s[n] >= kEnhancedHu ? kSmoothEnhanced : 0));
            }
        });
    return smoothClass;
}

/// Is @p bit set in voxel @p i's class byte?
bool smoothIs(const std::vector<std::uint8_t>& smoothClass, std::size_t i, std::uint8_t bit)
{
    return (smoothClass[i] & bit) != 0;
}

/// The unsmoothed HU of @p lat, dense.
std::vector<float> denseHu(const Lattice& lat, const volume::FloatGrid& huGrid)
{
    std::vector<float> hu(lat.size());
    openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> dense(latticeBox(lat), hu.data());
    if (!hu.empty()) openvdb::tools::copyToDense(huGrid, dense, /*serial=*/false);
    return hu;
}

/// Step 2: lung among the gas components.
Mask lungAmongGas(
    const Lattice& lat, const Mask& body, const std::vector<std::uint8_t>& smoothClass, const std::vector<float>& hu)
{
    const Mask gas =
        maskWhere(lat.size(), [&](std::size_t i) { return body[i] && smoothIs(smoothClass, i, kSmoothGas); });
    const ComponentRuns cc = componentRuns(lat, gas, Span::Volume);
    std::vector<std::int64_t> pureAir(cc.list.size() + 1, 0);
    const std::size_t nx = std::size_t(lat.dims.x());
    for (std::size_t r = 0; r < cc.runs.size(); ++r) {
        const std::size_t base = std::size_t(cc.runs[r].row) * nx;
        for (int i = cc.runs[r].begin; i < cc.runs[r].end; ++i)
            pureAir[std::size_t(cc.of[r])] += hu[base + std::size_t(i)] < kPureAirHu;
    }
    std::vector<std::uint8_t> isLung(cc.list.size() + 1, 0);
    for (std::size_t c = 0; c < cc.list.size(); ++c) {
        const double ml = double(cc.list[c].voxels) * lat.voxelMl();
        const double air = double(pureAir[c + 1]) / double(cc.list[c].voxels);
        isLung[c + 1] = ml >= kLungMinMl && air <= kLungMaxPureAirFraction;
    }
    Mask lungMask = cc.mask(lat, isLung);
    fillHolesPerSlice(lat, lungMask); // vessels and airways inside the lung are lung
    return maskAnd(lungMask, body);
}

/// Step 3's voxels: bright in the smoothed or the unsmoothed HU, in the body, not lung.
Mask enhancedMask(const Lattice& lat, const Mask& body, const Mask& lungMask,
    const std::vector<std::uint8_t>& smoothClass, const std::vector<float>& hu)
{
    return maskWhere(lat.size(), [&](std::size_t i) {
        return body[i] && !lungMask[i] && (smoothIs(smoothClass, i, kSmoothEnhanced) || hu[i] >= kBoneHu);
    });
}

/// Step 3: the enhanced structures split by erosion and grown back, one id
/// per region in @p region. Returns the number of regions.
int enhancedRegions(
    const Lattice& lat, const Mask& enhanced, const std::vector<float>& hu, std::vector<std::int32_t>& region)
{
    // Cores from the unsmoothed bone threshold: smoothing bridges the thin fat
    // planes between organs, and the erosion would no longer split them.
    const Mask bright = maskWhere(lat.size(), [&](std::size_t i) { return enhanced[i] && hu[i] >= kBoneHu; });
    const ComponentRuns cores = componentRuns(lat, erode(lat, bright, kCoreErosionMm, Span::Volume), Span::Volume);
    cores.forEachRun(lat, [&](std::int32_t c, std::size_t b, std::size_t e) {
        std::fill(region.begin() + std::ptrdiff_t(b), region.begin() + std::ptrdiff_t(e), c);
    });
    growRegions(lat, region, enhanced);
    // Structures thinner than twice the erosion (ribs, laminae, small vessels) have no
    // core: their bright voxels become regions of their own, classified like the rest.
    const ComponentRuns thin =
        componentRuns(lat, maskWhere(lat.size(), [&](std::size_t i) { return bright[i] && !region[i]; }), Span::Volume);
    const auto offset = std::int32_t(cores.list.size());
    thin.forEachRun(lat, [&](std::int32_t c, std::size_t b, std::size_t e) {
        std::fill(region.begin() + std::ptrdiff_t(b), region.begin() + std::ptrdiff_t(e), offset + c);
    });
    growRegions(lat, region, enhanced);
    return int(cores.list.size() + thin.list.size());
}

enum class RegionKind : std::uint8_t {
    None,
    Bone,
    Aorta,
    Kidney,
    Other
};

/// Step 3's classification: bone by its dense fraction, then, placed from the
/// spine (the largest bone), the aorta and the kidneys among the rest.
std::vector<RegionKind> classifyRegions(const Lattice& lat, const std::vector<RegionStats>& stats, int regions)
{
    std::vector<RegionKind> kind(std::size_t(regions) + 1, RegionKind::None);
    int largestBone = 0;
    for (int r = 1; r <= regions; ++r) {
        const RegionStats& s = stats[std::size_t(r)];
        if (!s.voxels) continue;
        kind[std::size_t(r)] =
            double(s.dense) >= kBoneDenseFraction * double(s.voxels) ? RegionKind::Bone : RegionKind::Other;
        if (kind[std::size_t(r)] == RegionKind::Bone &&
            (!largestBone || s.voxels > stats[std::size_t(largestBone)].voxels)) {
            largestBone = r;
        }
    }
    const double spineX = largestBone ? stats[std::size_t(largestBone)].centreX : 0.0;
    const double spineY = largestBone ? stats[std::size_t(largestBone)].centreY : 0.0;
    int bestAorta = 0;
    for (int r = 1; r <= regions; ++r) {
        if (kind[std::size_t(r)] != RegionKind::Other) continue;
        const RegionStats& s = stats[std::size_t(r)];
        const double lateral = std::abs(s.centreX - spineX), ml = s.ml(lat), median = s.medianHu();
        if (s.lengthMm(lat) >= kAortaMinLengthMm && s.meanAreaMm2(lat) >= kAortaMinAreaMm2 &&
            s.meanAreaMm2(lat) <= kAortaMaxAreaMm2 && lateral < kKidneyMinLateralMm &&
            std::abs(s.centreY - spineY) <= kAortaMaxAnteriorMm) {
            // Of several tubes (the vena cava in a venous phase), the aorta is the longest.
            if (!bestAorta || s.voxels > stats[std::size_t(bestAorta)].voxels) bestAorta = r;
        } else if (ml >= kKidneyMinMl && ml <= kKidneyMaxMl && median >= kKidneyMinHu && median <= kKidneyMaxHu &&
            lateral >= kKidneyMinLateralMm && lateral <= kKidneyMaxLateralMm &&
            std::abs(s.centreY - spineY) <= kKidneyMaxAnteriorMm) {
            kind[std::size_t(r)] = RegionKind::Kidney;
        }
    }
    if (bestAorta) kind[std::size_t(bestAorta)] = RegionKind::Aorta;
    return kind;
}

/// Steps 3–4: one label per body voxel, written over its region id in @p labels.
void labelVoxels(const Lattice& lat, const CtTissues& t, const std::vector<RegionKind>& kind, const Mask& body,
    const Mask& lungMask, const std::vector<std::uint8_t>& smoothClass, const std::vector<float>& hu,
    std::vector<std::int32_t>& labels)
{
    forEachVoxel(lat.size(), [&](std::size_t i) {
        const RegionKind k = kind[std::size_t(labels[i])];
        if (!body[i]) {
            labels[i] = volume::kAirLabel;
            return;
        }
        const auto byHu = [&] {
            if (smoothIs(smoothClass, i, kSmoothGas)) return volume::kAirLabel; // bowel gas: no resistance, like air
            return smoothIs(smoothClass, i, kSmoothBelowFat) ? t.fat : t.muscle;
        };
        if (lungMask[i]) {
            labels[i] = t.lung;
            return;
        }
        switch (k) {
        case RegionKind::Bone:
            labels[i] = hu[i] >= kBoneHu ? (hu[i] >= t.corticalHu ? t.cortical : t.cancellous) : byHu();
            break;
        case RegionKind::Aorta:
            labels[i] = t.aorta;
            break;
        case RegionKind::Kidney:
            labels[i] = t.kidney;
            break;
        case RegionKind::Other:
            labels[i] = t.soft;
            break;
        case RegionKind::None:
            labels[i] = byHu();
            break;
        }
    });
}

/// Label @p as the in-plane holes of labels @p a and @p b up to @p maxMm2.
void fillSmallHoles(const Lattice& lat, std::vector<std::int32_t>& labels, std::int32_t a, std::int32_t b,
    std::int32_t as, double maxMm2)
{
    const Mask m = maskWhere(lat.size(), [&](std::size_t i) { return labels[i] == a || labels[i] == b; });
    Mask filled = m;
    fillHolesPerSlice(lat, filled);
    const Mask holes = filterSliceIslands(lat, maskAndNot(filled, m), 0.0, maxMm2);
    forEachVoxel(lat.size(), [&](std::size_t i) {
        if (holes[i]) labels[i] = as;
    });
}

/// Step 6: the spinal canal. @p lungMask is taken to drop it early.
void markSpinalCanal(
    const Lattice& lat, const CtTissues& t, const Mask& body, Mask lungMask, std::vector<std::int32_t>& labels)
{
    // Each mask is dropped once read for the last time: this step holds the most at once.
    Mask bone =
        maskWhere(lat.size(), [&](std::size_t i) { return labels[i] == t.cortical || labels[i] == t.cancellous; });
    Mask hole;
    {
        const Mask ring = close(lat, bone, kCanalClosingMm, Span::Slice);
        Mask filled = ring;
        fillHolesPerSlice(lat, filled);
        filled = maskAndNot(filled, ring);
        hole = filterSliceIslands(lat, filled, kCanalMinAreaMm2, kCanalMaxAreaMm2);
    }
    const Mask soft3 = maskWhere(lat.size(), [&](std::size_t i) { return body[i] && !bone[i] && !lungMask[i]; });
    bone = {};
    lungMask = {};
    bridgeAlongSliceAxis(lat, hole, soft3, kCanalBridgeMm);
    // The canal is the soft tissue of those holes, the closing's ring excluded: the
    // ring's inner edge follows the bone except across the gaps it bridged.
    hole = maskAnd(hole, soft3);
    const ComponentRuns cc = componentRuns(lat, hole, Span::Volume);
    std::vector<std::uint8_t> keep(cc.list.size() + 1, 0);
    for (std::size_t c = 0; c < cc.list.size(); ++c) {
        const Component& k = cc.list[c];
        const double length = (k.max[lat.sliceAxis] - k.min[lat.sliceAxis] + 1) * lat.spacing[lat.sliceAxis];
        keep[c + 1] = length >= kCanalMinLengthMm;
    }
    cc.forEachRun(lat, [&](std::int32_t c, std::size_t b, std::size_t e) {
        if (keep[std::size_t(c)])
            std::fill(labels.begin() + std::ptrdiff_t(b), labels.begin() + std::ptrdiff_t(e), t.canal);
    });
}

/// Outside the torso range the trunk's rules do not hold: keep what CT numbers
/// say anywhere (skin, fat, bone, gas, lung), the rest is soft tissue. The box
/// keeps the whole slice axis, so its slice numbers are the volume's.
void softenOutsideTorso(
    const Lattice& lat, const CtTissues& t, const TorsoExtent& extent, std::vector<std::int32_t>& labels)
{
    if (extent.all()) return;
    const std::size_t stride = lat.strides()[std::size_t(lat.sliceAxis)];
    const auto slices = std::size_t(lat.dims[lat.sliceAxis]);
    forEachVoxel(lat.size(), [&](std::size_t i) {
        const std::int32_t l = labels[i];
        const bool trunkClass = l == t.muscle || l == t.kidney || l == t.aorta || l == t.canal;
        if (trunkClass && !extent.inTorso(int((i / stride) % slices))) labels[i] = t.soft;
    });
}

} // namespace

AutomaticLabels segmentCt(
    const volume::Volume& v, const Lattice& full, const volume::FloatGrid& huGrid, const volume::TissueTable& table)
{
    const CtTissues t = ctTissues(table);
    AutomaticLabels out;

    // Step 1 on the whole box; the body mask works slice by slice.
    std::vector<std::uint8_t> smoothClass = smoothedClasses(full, huGrid, t.fatMaxHu);
    Mask body =
        bodyMask(full, maskWhere(full.size(), [&](std::size_t i) { return smoothIs(smoothClass, i, kSmoothBody); }));
    out.extent = torsoExtent(v, full, body);

    // The rest on the body's box only (bodyBox says why the labels do not change).
    const Lattice lat = bodyBox(full, body, kCanalClosingMm);
    if (lat.dims != full.dims) {
        body = cropArray(full, lat, body);
        smoothClass = cropArray(full, lat, smoothClass);
    }
    std::vector<float> hu = denseHu(lat, huGrid);
    Mask lungMask = lungAmongGas(lat, body, smoothClass, hu);

    // The region ids become the labels in place (step 3–4), so one 32-bit array serves both.
    std::vector<std::int32_t> region(lat.size(), 0);
    const int regions = enhancedRegions(lat, enhancedMask(lat, body, lungMask, smoothClass, hu), hu, region);
    const std::vector<RegionKind> kind = classifyRegions(lat, regionStats(v, lat, region, regions, hu), regions);
    std::vector<std::int32_t>& labels = region;
    labelVoxels(lat, t, kind, body, lungMask, smoothClass, hu, labels);
    hu = {};
    smoothClass = {};

    // Small holes in bone (marrow fat, noise) are bone; the kidney's sinus and
    // medulla (darker than the cortex in the arterial phase) are kidney.
    fillSmallHoles(lat, labels, t.cortical, t.cancellous, t.cancellous, kBoneHoleMaxMm2);
    fillSmallHoles(lat, labels, t.kidney, t.kidney, t.kidney, 1e300);
    markSpinalCanal(lat, t, body, std::move(lungMask), labels);
    softenOutsideTorso(lat, t, out.extent, labels);
    if (std::string note = torsoNote(v, full, out.extent, "CT torso rules",
            "there muscle, kidney, aorta and spinal canal are not labelled (what those rules "
            "would call them is soft_tissue); skin, fat, bone, gas and lung are labelled from "
            "their CT numbers");
        !note.empty()) {
        out.notes.push_back(std::move(note));
    }

    markSkin(lat, body, t.skinMm, t.skin, labels);
    out.lattice = lat;
    out.labels = std::move(labels);
    return out;
}

} // namespace voxhap::segmentation
