// SPDX-License-Identifier: Apache-2.0
/// @file T1Normalisation.cpp
/// @brief Per-scan T1-weighted → T1 normalisation (physics.md §5.1).

#include "volume/mr/T1Normalisation.h"

#include "core/Errors.h"
#include "volume/Grids.h"

#include <openvdb/tree/LeafManager.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

namespace voxhap::volume {

namespace {

/// Bins of the intensity histogram the Otsu split runs on. 256 resolves the
/// fat/muscle contrast of T1w scans (about 2:1) to well under 1 % of the range;
/// the medians are then taken exactly, not from bins.
constexpr int kBins = 256;
/// Fraction of voxels cut at each end before binning, so that one corrupt
/// value (65535) or a bright vessel does not squash the histogram.
constexpr double kTailFraction = 1e-3;
/// Each of the fat and muscle classes must hold at least this fraction of the
/// voxels: fewer, and the scan does not show both tissues.
constexpr double kMinClassFraction = 0.01;

struct Histogram {
    double lo = 0, width = 1;
    std::array<double, kBins> count{};
    int bin(double v) const { return std::clamp(int((v - lo) / width), 0, kBins - 1); }
    double lowerEdge(int b) const { return lo + b * width; }
};

/// The two thresholds (bin indices t1 < t2: classes [0,t1), [t1,t2), [t2,kBins))
/// that maximise the between-class variance (Otsu 1979, three classes).
std::pair<int, int> otsu3(const Histogram& h)
{
    std::array<double, kBins + 1> w{}, m{}; // prefix sums of count and count·bin
    for (int b = 0; b < kBins; ++b) {
        w[std::size_t(b) + 1] = w[std::size_t(b)] + h.count[std::size_t(b)];
        m[std::size_t(b) + 1] = m[std::size_t(b)] + h.count[std::size_t(b)] * (b + 0.5);
    }
    const auto term = [&](int a, int b) { // w·μ² of class [a,b), 0 if empty
        const double wc = w[std::size_t(b)] - w[std::size_t(a)];
        const double mc = m[std::size_t(b)] - m[std::size_t(a)];
        return wc > 0 ? mc * mc / wc : 0.0;
    };
    double best = -1;
    std::pair<int, int> arg{1, 2};
    for (int t1 = 1; t1 < kBins - 1; ++t1) {
        for (int t2 = t1 + 1; t2 < kBins; ++t2) {
            // Σ w_k μ_k² differs from the between-class variance by a constant.
            const double s = term(0, t1) + term(t1, t2) + term(t2, kBins);
            if (s > best) {
                best = s;
                arg = {t1, t2};
            }
        }
    }
    return arg;
}

/// Exact median of the values in [lo, hi).
double medianIn(const FloatGrid& g, double lo, double hi, std::int64_t& n)
{
    std::vector<float> values;
    for (auto it = g.cbeginValueOn(); it; ++it) {
        const double v = *it;
        if (v >= lo && v < hi) values.insert(values.end(), it.getVoxelCount(), *it);
    }
    n = std::int64_t(values.size());
    if (values.empty()) return 0;
    auto mid = values.begin() + std::ptrdiff_t(values.size() / 2);
    std::nth_element(values.begin(), mid, values.end());
    return *mid;
}

std::string number(double v)
{
    std::ostringstream s;
    s << v;
    return s.str();
}

} // namespace

double T1wNormalisation::t1Ms(double s) const
{
    const double rFat = 1.0 / fatT1Ms, rMuscle = 1.0 / muscleT1Ms;
    const double rate = rFat + (s - fatIntensity) * (rMuscle - rFat) / (muscleIntensity - fatIntensity);
    if (!(rate > 1.0 / kMaxT1Ms)) return kMaxT1Ms; // also catches NaN input
    return std::clamp(1.0 / rate, kMinT1Ms, kMaxT1Ms);
}

T1wNormalisation fitT1wNormalisation(
    const Volume& v, const TissueTable& table, FieldStrength field, const std::string& source)
{
    const auto grid = t1Grid(v);
    if (!grid) throw ValueError(source + ": no t1 channel to normalise");
    const Tissue& fat = table.at("fat");
    const Tissue& muscle = table.at("muscle");

    // Range without the tails: a fine first histogram over [min, max].
    float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
    double total = 0;
    for (auto it = grid->cbeginValueOn(); it; ++it) {
        if (!std::isfinite(*it)) throw ValueError(source + ": t1 channel holds a non-finite value");
        lo = std::min(lo, *it);
        hi = std::max(hi, *it);
        total += double(it.getVoxelCount());
    }
    if (total < 100 || !(hi > lo))
        throw ValueError(source + ": too few distinct T1-weighted values to find fat and muscle");
    constexpr int kFine = 1 << 16;
    std::vector<double> fine(kFine, 0.0);
    const double fineWidth = (double(hi) - lo) / kFine;
    for (auto it = grid->cbeginValueOn(); it; ++it) {
        fine[std::size_t(std::clamp(int((*it - lo) / fineWidth), 0, kFine - 1))] += double(it.getVoxelCount());
    }
    int first = 0, last = kFine - 1;
    for (double c = 0; (c += fine[std::size_t(first)]) < kTailFraction * total;) ++first;
    for (double c = 0; (c += fine[std::size_t(last)]) < kTailFraction * total;) --last;

    Histogram h;
    h.lo = lo + first * fineWidth;
    h.width = std::max((last + 1 - first) * fineWidth / kBins, fineWidth);
    for (auto it = grid->cbeginValueOn(); it; ++it) h.count[std::size_t(h.bin(*it))] += double(it.getVoxelCount());
    const auto [t1, t2] = otsu3(h);

    T1wNormalisation fit;
    fit.field = field;
    fit.fatT1Ms = fat.t1(field);
    fit.muscleT1Ms = muscle.t1(field);
    fit.lowerThreshold = h.lowerEdge(t1);
    fit.upperThreshold = h.lowerEdge(t2);
    // The clamped tails belong to the outer classes.
    fit.muscleIntensity = medianIn(*grid, fit.lowerThreshold, fit.upperThreshold, fit.muscleVoxels);
    fit.fatIntensity = medianIn(*grid, fit.upperThreshold, std::numeric_limits<double>::infinity(), fit.fatVoxels);
    const double minClass = kMinClassFraction * total;
    if (double(fit.fatVoxels) < minClass || double(fit.muscleVoxels) < minClass ||
        !(fit.fatIntensity > fit.muscleIntensity)) {
        throw ValueError(source + ": no bright fat class above a muscle class in the T1-weighted intensities (fat " +
            number(fit.fatIntensity) + " in " + std::to_string(fit.fatVoxels) + " voxels, muscle " +
            number(fit.muscleIntensity) + " in " + std::to_string(fit.muscleVoxels) + ")");
    }
    return fit;
}

void applyT1wNormalisation(Volume& v, const T1wNormalisation& fit)
{
    const auto source = t1Grid(v);
    if (!source) throw ValueError("applyT1wNormalisation: no t1 channel");
    // Grids are shared read-only once set: transform a copy.
    FloatGrid::Ptr out = source->deepCopy();
    // Tiles serially, leaves one task each: every value is mapped exactly once.
    auto tile = out->tree().beginValueOn();
    tile.setMaxDepth(FloatGrid::TreeType::ValueOnIter::LEAF_DEPTH - 1);
    for (; tile; ++tile) tile.setValue(float(fit.t1Ms(*tile)));
    openvdb::tree::LeafManager<FloatGrid::TreeType>(out->tree())
        .foreach ([&](FloatGrid::TreeType::LeafNodeType& leaf, std::size_t) {
            for (auto it = leaf.beginValueOn(); it; ++it) it.setValue(float(fit.t1Ms(*it)));
        });
    v.setGrid(Channel::T1, out);

    VolumeMetadata& md = v.metadata();
    md.t1Units = "ms";
    md.t1Kind = T1Kind::NormalisedWeighted;
    md.extra["t1_norm_rule"] = "physics.md 5.1: fat and muscle of this scan pinned to the tissue table at " +
        std::string(fieldStrengthName(fit.field)) + "; linear in 1/T1 between them";
    md.extra["t1_norm_fat"] = number(fit.fatIntensity) + " -> " + number(fit.fatT1Ms) + " ms";
    md.extra["t1_norm_muscle"] = number(fit.muscleIntensity) + " -> " + number(fit.muscleT1Ms) + " ms";
    md.extra["t1_norm_thresholds"] = number(fit.lowerThreshold) + ", " + number(fit.upperThreshold);
}

} // namespace voxhap::volume
