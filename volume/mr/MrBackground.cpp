// SPDX-License-Identifier: Apache-2.0
/// @file MrBackground.cpp
/// @brief The MR background rule (MrBackground.h): noise floor, threshold,
/// largest component, holes filled, applied to the grid's activity.

#include "volume/mr/MrBackground.h"

#include "core/Errors.h"
#include "volume/Grids.h"

#include <openvdb/tools/Prune.h>
#include <openvdb/tree/LeafManager.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

namespace voxhap::volume {

namespace mrbackground_detail {

/// The noise peak is found in the low histogram smoothed over 1/kModeWindow of
/// its bins (a moving average; MrBackground.h step 2).
constexpr std::size_t kModeWindow = 64;

using FloatTree = FloatGrid::TreeType;
using FloatLeaf = FloatTree::LeafNodeType;

/// Marks of the dense mask.
enum Mark : std::uint8_t {
    kBelow = 0,   ///< below the threshold (or inactive, or outside the grid's data)
    kAbove = 1,   ///< at or above the threshold, not yet visited
    kSpeck = 2,   ///< above, visited: a component other than the largest
    kBody = 3,    ///< the largest component
    kOutside = 4, ///< reached by the flood from the border: background
};

/// The dense extent as a flat array, x fastest.
struct DenseLayout {
    Vec3i min{0, 0, 0};
    std::int64_t nx = 0, ny = 0, nz = 0;
    std::int64_t index(std::int64_t x, std::int64_t y, std::int64_t z) const { return x + nx * (y + ny * z); }
    std::int64_t size() const { return nx * ny * nz; }
};

/// The in-box part of a leaf: index-space bounds, inclusive.
bool leafInBox(const FloatLeaf& leaf, const openvdb::CoordBBox& box, openvdb::CoordBBox& clipped)
{
    clipped = leaf.getNodeBoundingBox();
    clipped.intersect(box);
    return !clipped.empty();
}

/// Visit every leaf that meets the box, in parallel: f(leaf, clipped) with
/// @p clipped the in-box part of the leaf (index space, inclusive).
template <typename F>
void forEachLeafInBox(openvdb::tree::LeafManager<FloatTree>& leaves, const openvdb::CoordBBox& box, const F& f)
{
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, leaves.leafCount(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t n = r.begin(); n < r.end(); ++n) {
                FloatLeaf& leaf = leaves.leaf(n);
                openvdb::CoordBBox c;
                if (leafInBox(leaf, box, c)) f(leaf, c);
            }
        });
}

/// Visit the voxels of @p c (the in-box part of one leaf): f(offset, x, y, z)
/// with x, y, z relative to the box minimum.
template <typename F> void forEachVoxel(const openvdb::CoordBBox& c, const openvdb::CoordBBox& box, const F& f)
{
    for (int z = c.min().z(); z <= c.max().z(); ++z) {
        for (int y = c.min().y(); y <= c.max().y(); ++y) {
            openvdb::Index offset = FloatLeaf::coordToOffset(openvdb::Coord(c.min().x(), y, z));
            for (int x = c.min().x(); x <= c.max().x(); ++x, offset += FloatLeaf::DIM * FloatLeaf::DIM) {
                f(offset, x - box.min().x(), y - box.min().y(), z - box.min().z());
            }
        }
    }
}

/// One pass over the active in-box values: range, count, integrality.
struct ValueRange {
    double lo = std::numeric_limits<double>::infinity();
    double hi = -std::numeric_limits<double>::infinity();
    std::int64_t positive = 0; ///< active voxels in the box with a value > 0
    bool integer = true;       ///< every value is a whole number
};

/// A histogram of equal bins over [lo, lo + width·count.size()); values
/// outside clamp to the end bins.
struct Histogram {
    double lo = 0, width = 1;
    std::vector<std::int64_t> count;
    std::int64_t bin(double v) const
    {
        return std::clamp(std::int64_t(std::floor((v - lo) / width)), std::int64_t(0), std::int64_t(count.size()) - 1);
    }
    double lowerEdge(std::int64_t b) const { return lo + double(b) * width; }
};

/// The value below which a fraction @p p of @p total voxels lies (bin lower edge).
double percentile(const Histogram& h, std::int64_t total, double p)
{
    const double target = p * double(total);
    double c = 0;
    for (std::size_t b = 0; b < h.count.size(); ++b) {
        c += double(h.count[b]);
        if (c > target) return h.lowerEdge(std::int64_t(b));
    }
    return h.lowerEdge(std::int64_t(h.count.size()) - 1);
}

/// Probability of [a, b) under a Rayleigh distribution (difference of the survival functions: accurate in the tail).
double rayleighMass(double a, double b, double sigma)
{
    const auto survival = [&](double x) { return x <= 0 ? 1.0 : std::exp(-x * x / (2 * sigma * sigma)); };
    return survival(a) - survival(b);
}

/// Maximum-likelihood σ of a Rayleigh distribution truncated to [e[0], e[K]),
/// from the counts n[k] of bins [e[k], e[k+1]) (Sijbers et al. 2007: the
/// multinomial likelihood of the partial histogram). Golden-section search on
/// ln σ in [lo, hi].
double fitRayleigh(const std::vector<double>& edges, const std::vector<double>& n, double lo, double hi)
{
    const auto negLogLikelihood = [&](double logSigma) {
        const double s = std::exp(logSigma);
        const double total = rayleighMass(edges.front(), edges.back(), s);
        double l = 0;
        for (std::size_t k = 0; k + 1 < edges.size(); ++k) {
            if (n[k] <= 0) continue;
            const double p = rayleighMass(edges[k], edges[k + 1], s) / total;
            l -= n[k] * std::log(std::max(p, 1e-300));
        }
        return l;
    };
    const double phi = (std::sqrt(5.0) - 1) / 2;
    double a = std::log(lo), b = std::log(hi);
    double c = b - phi * (b - a), d = a + phi * (b - a);
    double fc = negLogLikelihood(c), fd = negLogLikelihood(d);
    for (int i = 0; i < 80 && b - a > 1e-7; ++i) {
        if (fc < fd) {
            b = d;
            d = c;
            fd = fc;
            c = b - phi * (b - a);
            fc = negLogLikelihood(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + phi * (b - a);
            fd = negLogLikelihood(d);
        }
    }
    return std::exp((a + b) / 2);
}

/// Kolmogorov distance between the partial histogram and the Rayleigh of mode
/// @p sigma truncated to the same range.
double rayleighDistance(const std::vector<double>& edges, const std::vector<double>& n, double sigma)
{
    double total = 0;
    for (double c : n) total += c;
    if (total <= 0) return 1.0;
    const double mass = rayleighMass(edges.front(), edges.back(), sigma);
    double observed = 0, worst = 0;
    for (std::size_t k = 0; k + 1 < edges.size(); ++k) {
        observed += n[k] / total;
        const double model = rayleighMass(edges.front(), edges[k + 1], sigma) / mass;
        worst = std::max(worst, std::abs(observed - model));
    }
    return worst;
}

/// 6-connected scanline flood fill over a dense mask: every voxel reachable
/// from the seeds through voxels where enter(mark) holds is set to @p to
/// (for which enter() must be false). Returns the number of voxels set.
/// @param stack scratch, reused between calls
template <typename Enter>
std::int64_t floodFill(std::uint8_t* m, const DenseLayout& d, std::vector<std::array<std::int32_t, 3>>& stack,
    const Enter& enter, std::uint8_t to)
{
    std::int64_t filled = 0;
    while (!stack.empty()) {
        const auto [sx, sy, sz] = stack.back();
        stack.pop_back();
        std::uint8_t* row = m + d.index(0, sy, sz);
        if (!enter(row[sx])) continue;
        std::int64_t x0 = sx, x1 = sx;
        while (x0 > 0 && enter(row[x0 - 1])) --x0;
        while (x1 + 1 < d.nx && enter(row[x1 + 1])) ++x1;
        std::fill(row + x0, row + x1 + 1, to);
        filled += x1 - x0 + 1;
        const std::array<std::array<std::int64_t, 2>, 4> neighbours{
            {{sy - 1, sz}, {sy + 1, sz}, {sy, sz - 1}, {sy, sz + 1}}};
        for (const auto& [ny, nz] : neighbours) {
            if (ny < 0 || ny >= d.ny || nz < 0 || nz >= d.nz) continue;
            const std::uint8_t* next = m + d.index(0, ny, nz);
            for (std::int64_t x = x0; x <= x1; ++x) {
                if (enter(next[x]) && (x == x0 || !enter(next[x - 1]))) {
                    stack.push_back({std::int32_t(x), std::int32_t(ny), std::int32_t(nz)});
                }
            }
        }
    }
    return filled;
}

/// Number formatting for the rule line: 4 significant digits.
std::string num(double v)
{
    std::ostringstream s;
    s.precision(4);
    s << v;
    return s.str();
}

/// The noise model found in the histograms.
struct NoiseEstimate {
    double t2 = 0, t98 = 0, bet = 0; ///< robust range and BET's threshold
    double mode = 0;                 ///< histogram mode of the positive values below tBET (0: none)
    double sigma = 0;                ///< Rayleigh fit (0: none)
    double distance = 1;             ///< Kolmogorov distance of the fit
    double population = 0;           ///< voxels the fitted Rayleigh population stands for
    bool rayleigh = false;           ///< the peak is accepted as noise
    std::int64_t zeros = 0;          ///< in-box voxels ≤ 0 or inactive
    double minPositive = 0;          ///< smallest positive value
    std::string why;                 ///< why the peak was rejected, if it was
};

/// Bins of the robust-range histogram (pass 2) for data that are not integers
/// or do not fit unit bins.
constexpr std::int64_t kRangeBins = std::int64_t(1) << 16;

/// Pass 1: range and integrality of the active in-box values.
ValueRange activeRange(openvdb::tree::LeafManager<FloatTree>& leaves, const openvdb::CoordBBox& box)
{
    tbb::enumerable_thread_specific<ValueRange> ranges;
    forEachLeafInBox(leaves, box, [&](const FloatLeaf& leaf, const openvdb::CoordBBox& c) {
        ValueRange& r = ranges.local();
        forEachVoxel(c, box, [&](openvdb::Index i, int, int, int) {
            if (!leaf.isValueOn(i)) return;
            const double v = leaf.getValue(i);
            if (!(v > 0)) return; // zeros, negatives (and NaN) count as background
            ++r.positive;
            r.lo = std::min(r.lo, v);
            r.hi = std::max(r.hi, v);
            if (r.integer && v != std::floor(v)) r.integer = false;
        });
    });
    ValueRange all;
    for (const ValueRange& r : ranges) {
        all.lo = std::min(all.lo, r.lo);
        all.hi = std::max(all.hi, r.hi);
        all.positive += r.positive;
        all.integer = all.integer && r.integer;
    }
    return all;
}

/// Add the active in-box values for which counted(value) holds to @p h.
template <typename Counted>
void countValues(
    openvdb::tree::LeafManager<FloatTree>& leaves, const openvdb::CoordBBox& box, Histogram& h, const Counted& counted)
{
    tbb::enumerable_thread_specific<std::vector<std::int64_t>> local(
        [&] { return std::vector<std::int64_t>(h.count.size(), 0); });
    forEachLeafInBox(leaves, box, [&](const FloatLeaf& leaf, const openvdb::CoordBBox& c) {
        std::vector<std::int64_t>& counts = local.local();
        forEachVoxel(c, box, [&](openvdb::Index i, int, int, int) {
            if (!leaf.isValueOn(i)) return;
            const double v = leaf.getValue(i);
            if (counted(v)) ++counts[std::size_t(h.bin(v))];
        });
    });
    for (const auto& counts : local) {
        for (std::size_t b = 0; b < counts.size(); ++b) h.count[b] += counts[b];
    }
}

/// Pass 2: the robust range over all in-box voxels (the @p zeros in bin 0).
/// Integer data get unit bins centred on the integers while the range fits.
Histogram rangeHistogram(openvdb::tree::LeafManager<FloatTree>& leaves, const openvdb::CoordBBox& box,
    const ValueRange& all, std::int64_t zeros)
{
    Histogram range;
    if (all.integer && all.hi < double(kRangeBins) - 1) {
        range.lo = -0.5;
        range.width = 1.0;
        range.count.assign(std::size_t(all.hi + 1.5), 0);
    } else {
        range.lo = 0;
        range.width = std::max(all.hi / double(kRangeBins), std::numeric_limits<double>::min());
        range.count.assign(std::size_t(kRangeBins), 0);
    }
    countValues(leaves, box, range, [](double v) { return v > 0; });
    range.count[0] += zeros;
    return range;
}

/// Pass 3: the low histogram, positive values below tBET (@p bet).
/// Integer data: unit bins centred on the integers, else kLowBins bins.
Histogram lowHistogram(openvdb::tree::LeafManager<FloatTree>& leaves, const openvdb::CoordBBox& box,
    const ValueRange& all, const Histogram& range, double bet)
{
    constexpr std::int64_t kLowBins = 4096;
    Histogram low;
    if (all.integer && bet < double(kRangeBins)) {
        // Reuse pass 2's unit bins: bin b holds the integer b.
        low.lo = -0.5;
        low.width = 1.0;
        low.count.assign(range.count.begin(),
            range.count.begin() + std::ptrdiff_t(std::min<double>(double(range.count.size()), std::floor(bet) + 1)));
    } else {
        low.lo = 0;
        low.width = bet / double(kLowBins);
        low.count.assign(std::size_t(kLowBins), 0);
        countValues(leaves, box, low, [bet](double v) { return v > 0 && v < bet; });
    }
    return low;
}

/// The counts from bin @p first on, averaged over a moving window of
/// @p window bins centred on each (bins before @p first stay 0).
std::vector<double> movingAverage(const std::vector<std::int64_t>& count, std::size_t first, std::size_t window)
{
    std::vector<double> smooth(count.size(), 0.0);
    double sum = 0.0;
    std::size_t n = 0;
    const std::size_t half = window / 2;
    std::size_t lo = first, hi = first; // the window [lo, hi) around b
    for (std::size_t b = first; b < count.size(); ++b) {
        while (hi < count.size() && hi <= b + half) sum += double(count[hi++]), ++n;
        while (lo + half < b) sum -= double(count[lo++]), --n;
        smooth[b] = n ? sum / double(n) : 0.0;
    }
    return smooth;
}

/// The Rayleigh fit to the low peak at e.mode, and whether it is the air's
/// noise: close enough to a Rayleigh, and standing for enough voxels.
void fitNoisePeak(NoiseEstimate& e, const Histogram& low, std::size_t first, std::int64_t total)
{
    // The partial histogram up to kFitRangeModes modes, at least 3 bins.
    std::size_t last = std::max(first + 3, std::size_t(std::ceil((kFitRangeModes * e.mode - low.lo) / low.width)));
    last = std::min(last, low.count.size());
    std::vector<double> edges, counts;
    for (std::size_t b = first; b < last; ++b) {
        edges.push_back(low.lowerEdge(std::int64_t(b)));
        counts.push_back(double(low.count[b]));
    }
    edges.push_back(low.lowerEdge(std::int64_t(last)));
    e.sigma = fitRayleigh(edges, counts, 0.25 * e.mode, 4.0 * e.mode);
    e.distance = rayleighDistance(edges, counts, e.sigma);
    if (e.distance > kMaxRayleighDistance) {
        e.why = "the low peak at " + num(e.mode) + " is not Rayleigh noise (Kolmogorov distance " + num(e.distance) +
            " > " + num(kMaxRayleighDistance) + ")";
        return;
    }
    // How many voxels the fitted noise stands for: the fit range holds
    // mass(e0, eK) of the population.
    double inRange = 0;
    for (double c : counts) inRange += c;
    e.population = inRange / rayleighMass(edges.front(), edges.back(), e.sigma);
    if (e.population < kMinBackgroundFraction * double(total)) {
        e.why = "the low peak at " + num(e.mode) + " stands for only " + num(e.population) + " voxels (" +
            num(100.0 * e.population / double(total)) + " %)";
        return;
    }
    e.rayleigh = true;
}

NoiseEstimate estimateNoise(
    openvdb::tree::LeafManager<FloatTree>& leaves, const openvdb::CoordBBox& box, std::int64_t total)
{
    NoiseEstimate e;
    const ValueRange all = activeRange(leaves, box);
    e.zeros = total - all.positive;
    if (all.positive == 0) {
        e.why = "no positive value";
        return e;
    }
    e.minPositive = all.lo;

    const Histogram range = rangeHistogram(leaves, box, all, e.zeros);
    e.t2 = std::max(0.0, percentile(range, total, 0.02));
    e.t98 = percentile(range, total, 0.98);
    e.bet = e.t2 + kBetFraction * (e.t98 - e.t2);
    if (!(e.bet > 0)) {
        e.why = "no robust range (t2 = t98 = 0)";
        return e;
    }

    const Histogram low = lowHistogram(leaves, box, all, range, e.bet);
    // The zeros are not part of the noise fit: integer bin 0 is all zeros;
    // float bin 0 holds positive values only.
    const std::size_t first = all.integer ? 1 : 0;
    if (low.count.size() < first + 3) {
        e.why = "too few histogram bins below tBET";
        return e;
    }
    // The peak of the histogram smoothed over kModeWindow of its bins: the
    // Rayleigh's top is flat (within 5 % over ±0.3σ), and the argmax of the
    // raw bins wanders over it with their counting noise.
    const std::vector<double> smooth =
        movingAverage(low.count, first, std::max<std::size_t>(1, low.count.size() / kModeWindow));
    std::size_t peak = first;
    for (std::size_t b = first; b < low.count.size(); ++b) {
        if (smooth[b] > smooth[peak]) peak = b;
    }
    e.mode = low.lowerEdge(std::int64_t(peak)) + low.width / 2;
    if (low.count[peak] == 0 && smooth[peak] == 0.0) {
        e.why = "no positive value below tBET";
        return e;
    }
    if (e.mode > 0.5 * e.bet) {
        e.why = "no peak at the low end of the histogram (mode " + num(e.mode) + " above tBET/2 = " + num(0.5 * e.bet) +
            ")";
        return e;
    }
    fitNoisePeak(e, low, first, total);
    return e;
}

/// Steps 1–3 from the noise estimate: the threshold into @p result, and how it
/// was found into @p how. False when there is no air background to remove
/// (result.rule then says why).
bool chooseThreshold(const NoiseEstimate& noise, std::int64_t total, MrBackgroundResult& result, std::string& how)
{
    result.betThreshold = noise.bet;
    const double zeroPercent = 100.0 * double(noise.zeros) / double(total);
    if (noise.rayleigh) {
        const double k = mrNoiseMultiple(total);
        result.noiseFloor = noise.sigma;
        result.threshold = k * noise.sigma;
        how = "Rayleigh noise sigma " + num(noise.sigma) + " (histogram mode " + num(noise.mode) + " below tBET " +
            num(noise.bet) + ", ML fit below " + num(kFitRangeModes) + " modes, Kolmogorov distance " +
            num(noise.distance) + "); threshold " + num(k) + " sigma = " + num(result.threshold) +
            " (k = sqrt(2 ln N), N = " + std::to_string(total) + ")";
        return true;
    }
    if (double(noise.zeros) >= kMinBackgroundFraction * double(total) && noise.minPositive > 0) {
        // No noise peak, but zeros: the scanner masked the air.
        result.zeroBackground = true;
        result.noiseFloor = 0;
        result.threshold = noise.minPositive;
        how = "zero background (" + num(zeroPercent) + " % of the voxels are 0, no Rayleigh noise: " + noise.why +
            "); threshold: the smallest positive value, " + num(result.threshold);
        return true;
    }
    result.threshold = 0;
    result.rule = "MR background: none removed, no air background (no Rayleigh noise: " + noise.why + "; " +
        num(zeroPercent) + " % zeros)";
    return false;
}

/// Step 4's mask: kAbove where an active in-box value is at or above @p t.
std::vector<std::uint8_t> markAbove(
    openvdb::tree::LeafManager<FloatTree>& leaves, const openvdb::CoordBBox& box, const DenseLayout& d, float t)
{
    std::vector<std::uint8_t> mask(std::size_t(d.size()), kBelow);
    forEachLeafInBox(leaves, box, [&](const FloatLeaf& leaf, const openvdb::CoordBBox& c) {
        forEachVoxel(c, box, [&](openvdb::Index i, int x, int y, int z) {
            if (leaf.isValueOn(i) && leaf.getValue(i) >= t) mask[std::size_t(d.index(x, y, z))] = kAbove;
        });
    });
    return mask;
}

/// Step 4: every component of kAbove voxels becomes kSpeck, then the largest
/// kBody. Returns the number of components.
std::int64_t keepLargestComponent(
    std::uint8_t* m, const DenseLayout& d, std::vector<std::array<std::int32_t, 3>>& stack)
{
    std::int64_t components = 0, largest = 0;
    std::array<std::int32_t, 3> largestSeed{0, 0, 0};
    for (std::int64_t z = 0; z < d.nz; ++z) {
        for (std::int64_t y = 0; y < d.ny; ++y) {
            std::uint8_t* row = m + d.index(0, y, z);
            for (std::int64_t x = 0; x < d.nx; ++x) {
                if (row[x] != kAbove) continue;
                stack.push_back({std::int32_t(x), std::int32_t(y), std::int32_t(z)});
                const std::int64_t n = floodFill(
                    m, d, stack, [](std::uint8_t v) { return v == kAbove; }, kSpeck);
                ++components;
                if (n > largest) {
                    largest = n;
                    largestSeed = {std::int32_t(x), std::int32_t(y), std::int32_t(z)};
                }
            }
        }
    }
    if (largest > 0) {
        stack.push_back(largestSeed);
        floodFill(
            m, d, stack, [](std::uint8_t v) { return v == kSpeck; }, kBody);
    }
    return components;
}

/// Step 5: the flood from the border through everything but the body marks
/// kOutside. Returns the number of voxels it reached.
std::int64_t floodFromBorder(std::uint8_t* m, const DenseLayout& d, std::vector<std::array<std::int32_t, 3>>& stack)
{
    const auto outside = [](std::uint8_t v) { return v == kBelow || v == kSpeck; };
    std::int64_t removed = 0;
    const auto seedFace = [&](std::int64_t x, std::int64_t y, std::int64_t z) {
        if (!outside(m[d.index(x, y, z)])) return;
        stack.push_back({std::int32_t(x), std::int32_t(y), std::int32_t(z)});
        removed += floodFill(m, d, stack, outside, kOutside);
    };
    for (std::int64_t z = 0; z < d.nz; ++z) {
        for (std::int64_t y = 0; y < d.ny; ++y) {
            if (z == 0 || z == d.nz - 1 || y == 0 || y == d.ny - 1) {
                for (std::int64_t x = 0; x < d.nx; ++x) seedFace(x, y, z);
            } else {
                seedFace(0, y, z);
                seedFace(d.nx - 1, y, z);
            }
        }
    }
    return removed;
}

/// Step 6, first half: a leaf for every 8³ block that keeps a voxel and has
/// none (an enclosed hole the loader had left inactive).
void touchKeptLeaves(FloatTree& tree, const openvdb::CoordBBox& box, const DenseLayout& d, const std::uint8_t* m)
{
    const openvdb::Coord origin0 = box.min() & ~7;
    for (int bz = origin0.z(); bz <= box.max().z(); bz += 8) {
        for (int by = origin0.y(); by <= box.max().y(); by += 8) {
            for (int bx = origin0.x(); bx <= box.max().x(); bx += 8) {
                const openvdb::Coord origin(bx, by, bz);
                if (tree.probeConstLeaf(origin)) continue;
                openvdb::CoordBBox c(origin, origin.offsetBy(7));
                c.intersect(box);
                bool keep = false;
                for (int z = c.min().z(); z <= c.max().z() && !keep; ++z) {
                    for (int y = c.min().y(); y <= c.max().y() && !keep; ++y) {
                        for (int x = c.min().x(); x <= c.max().x() && !keep; ++x) {
                            keep = m[d.index(x - d.min.x(), y - d.min.y(), z - d.min.z())] != kOutside;
                        }
                    }
                }
                if (keep) tree.touchLeaf(origin);
            }
        }
    }
}

/// Step 6, second half: the mask per leaf, kOutside inactive background,
/// everything else active.
void applyMask(openvdb::tree::LeafManager<FloatTree>& leaves, const openvdb::CoordBBox& box, const DenseLayout& d,
    const std::uint8_t* m, float background)
{
    forEachLeafInBox(leaves, box, [&](FloatLeaf& leaf, const openvdb::CoordBBox& c) {
        forEachVoxel(c, box, [&](openvdb::Index i, int x, int y, int z) {
            if (m[d.index(x, y, z)] == kOutside) {
                leaf.setValueOff(i, background);
            } else {
                leaf.setValueOn(i);
            }
        });
    });
}

/// The rule itself (removeMrBackground checks the arguments). Inside this
/// namespace so that its names never meet those of other files of a unity batch.
MrBackgroundResult removeBackground(FloatGrid& grid, const IndexBox& indexBox)
{
    const auto start = std::chrono::steady_clock::now();
    FloatTree& tree = grid.tree();
    const openvdb::CoordBBox box = toCoordBBox(indexBox);
    const DenseLayout d{indexBox.min, indexBox.dims().x(), indexBox.dims().y(), indexBox.dims().z()};
    const std::int64_t total = d.size();

    MrBackgroundResult result;
    result.activeBefore = std::int64_t(tree.activeVoxelCount());
    const auto finish = [&](MrBackgroundResult& r) {
        r.activeAfter = std::int64_t(tree.activeVoxelCount());
        r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        return r;
    };

    // Every active value in a leaf, so that leaves are the only thing to
    // visit; constant leaves become tiles again at the end.
    const bool hadTiles = tree.activeTileCount() > 0;
    if (hadTiles) tree.voxelizeActiveTiles();
    openvdb::tree::LeafManager<FloatTree> leaves(tree);
    const auto unchanged = [&](MrBackgroundResult& r) {
        if (hadTiles) openvdb::tools::prune(tree);
        r.applied = false;
        return finish(r);
    };

    // 1–3: noise floor and threshold.
    std::string how;
    if (!chooseThreshold(estimateNoise(leaves, box, total), total, result, how)) return unchanged(result);

    // 4–5: mask, largest component, flood from the border.
    std::vector<std::uint8_t> mask = markAbove(leaves, box, d, float(result.threshold));
    std::uint8_t* m = mask.data();
    std::vector<std::array<std::int32_t, 3>> stack;
    result.components = keepLargestComponent(m, d, stack);
    const std::int64_t removed = floodFromBorder(m, d, stack);
    if (double(removed) < kMinBackgroundFraction * double(total)) {
        result.rule = "MR background: none removed, no air background (" + how + "; only " + std::to_string(removed) +
            " voxels outside the body reach the volume border)";
        return unchanged(result);
    }
    for (std::uint8_t v : mask) result.holesFilled += v == kBelow ? 1 : 0;

    // 6: apply.
    touchKeptLeaves(tree, box, d, m);
    leaves.rebuild();
    applyMask(leaves, box, d, m, grid.background());
    openvdb::tools::pruneInactive(tree);
    if (hadTiles) openvdb::tools::prune(tree);

    std::ostringstream rule;
    rule << "MR background: " << how << "; the largest of " << result.components
         << " 6-connected components kept and its holes filled (" << result.holesFilled
         << " voxels below the threshold not reached by a 6-connected flood from the border); " << removed
         << " voxels made inactive background";
    result.rule = rule.str();
    return finish(result);
}

} // namespace mrbackground_detail

MrBackgroundResult removeMrBackground(openvdb::GridBase& grid, const IndexBox& box)
{
    auto* floatGrid = dynamic_cast<FloatGrid*>(&grid);
    if (!floatGrid) throw ValueError("removeMrBackground: grid '" + grid.getName() + "' is not a float grid");
    if (box.empty()) throw ValueError("removeMrBackground: empty index box");
    return mrbackground_detail::removeBackground(*floatGrid, box);
}

} // namespace voxhap::volume
