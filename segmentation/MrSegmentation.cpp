// SPDX-License-Identifier: Apache-2.0
/// @file MrSegmentation.cpp
/// @brief Body mask, two-class Otsu, fluid rule and skin shell for MR T1.

#include "segmentation/MrSegmentation.h"

#include "segmentation/CtSegmentation.h"
#include "segmentation/Morphology.h"
#include "segmentation/detail/VoxelLoops.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace voxhap::segmentation {

namespace {

constexpr int kOtsuBins = 256;
// Fluid: T1 above twice the muscle class's median (CSF is five times muscle at
// 1.5 T, physics.md §5.1) [chosen].
constexpr double kFluidFactor = 2.0;

double medianOf(std::vector<float> v)
{
    if (v.empty()) return 0.0;
    const auto mid = v.begin() + std::ptrdiff_t(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
}

} // namespace

double otsuThreshold(const std::vector<float>& values)
{
    if (values.empty()) return 0.0;
    const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
    const double a = *lo, b = *hi;
    if (!(b > a)) return a;
    std::array<double, kOtsuBins> h{};
    for (float x : values) h[std::size_t(std::min(kOtsuBins - 1, int((x - a) / (b - a) * kOtsuBins)))] += 1.0;
    double total = 0, sumAll = 0;
    for (int i = 0; i < kOtsuBins; ++i) {
        total += h[std::size_t(i)];
        sumAll += i * h[std::size_t(i)];
    }
    double w0 = 0, sum0 = 0, best = -1;
    int split = 0;
    for (int t = 0; t < kOtsuBins - 1; ++t) {
        w0 += h[std::size_t(t)];
        sum0 += t * h[std::size_t(t)];
        const double w1 = total - w0;
        if (w0 == 0 || w1 == 0) continue;
        const double m0 = sum0 / w0, m1 = (sumAll - sum0) / w1;
        const double between = w0 * w1 * (m0 - m1) * (m0 - m1);
        if (between > best) {
            best = between;
            split = t;
        }
    }
    return a + (b - a) * double(split + 1) / kOtsuBins; // upper edge of the last bin of the lower class
}

std::vector<std::int32_t> segmentMr(const Lattice& lat, const std::vector<float>& t1, bool t1InMs,
                                    const volume::TissueTable& table)
{
    const auto id = [&](const char* name) { return std::int32_t(table.at(name).id); };
    const std::int32_t skin = id("skin"), fat = id("fat"), muscle = id("muscle"), soft = id("soft_tissue");
    const double skinMm = table.at("skin").thickness ? table.at("skin").thickness->value : 2.0;

    const Mask body = bodyMask(lat, detail::maskWhere(lat.size(), [&](std::size_t i) { return t1[i] > 0.0f; }));
    std::vector<float> inside;
    for (std::size_t n = 0; n < t1.size(); ++n) {
        if (body[n] && t1[n] > 0.0f) inside.push_back(t1[n]);
    }
    std::vector<std::int32_t> labels(lat.size(), volume::kAirLabel);
    if (inside.empty()) return labels;
    // Fluid first (the long tail would pull Otsu's split away from fat | muscle):
    // split once, take the non-fat class's median as muscle, cut the fluid, split again.
    double split = otsuThreshold(inside);
    const auto isFat = [&](float x) { return t1InMs ? x <= split : x > split; };
    std::vector<float> lean;
    for (float x : inside) {
        if (!isFat(x)) lean.push_back(x);
    }
    const double muscleMedian = medianOf(lean);
    const auto isFluid = [&](float x) { return t1InMs ? x > kFluidFactor * muscleMedian : x < muscleMedian / kFluidFactor; };
    std::vector<float> solid;
    for (float x : inside) {
        if (!isFluid(x)) solid.push_back(x);
    }
    split = otsuThreshold(solid);
    detail::forEachVoxel(lat.size(), [&](std::size_t i) {
        if (!body[i]) return;
        const float x = t1[i];
        if (x <= 0.0f) labels[i] = soft; // no signal inside the body: bone, air in the gut; T1 cannot tell
        else labels[i] = isFluid(x) ? soft : isFat(x) ? fat : muscle;
    });
    markSkin(lat, body, skinMm, skin, labels);
    return labels;
}

} // namespace voxhap::segmentation
