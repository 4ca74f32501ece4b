// SPDX-License-Identifier: Apache-2.0
/// @file MrSegmentation.cpp
/// @brief Body mask, two-class Otsu, fluid rule and skin shell for MR T1.

#include "segmentation/MrSegmentation.h"

#include "segmentation/CtSegmentation.h"
#include "segmentation/detail/VoxelLoops.h"
#include "segmentation/lattice/DistanceTransform.h"
#include "segmentation/lattice/Morphology.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <utility>

namespace voxhap::segmentation {

namespace {

constexpr int kOtsuBins = 256;
// Fluid: T1 above twice the muscle class's median (CSF is five times muscle at
// 1.5 T, physics.md §5.1) [chosen].
constexpr double kFluidFactor = 2.0;
// Outside the torso, fat is looked for only this deep under the skin [chosen]:
// the scalp (skin, subcutaneous fat, galea) is about 5–7 mm thick and the skull
// under it another 5–7 mm, so no brain lies within 10 mm of the skin; deeper fat
// (the orbits, the neck's deep compartments, a limb's thick subcutaneous layer)
// is left to soft_tissue rather than risk calling white matter fat.
constexpr double kSubcutaneousMm = 10.0;

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

AutomaticLabels segmentMr(const volume::Volume& v, const Lattice& lat, const std::vector<float>& values,
    MrContrast contrast, const volume::TissueTable& table)
{
    const auto id = [&](const char* name) { return std::int32_t(table.at(name).id); };
    const std::int32_t skin = id("skin"), fat = id("fat"), muscle = id("muscle"), soft = id("soft_tissue");
    const double skinMm = table.at("skin").thickness ? table.at("skin").thickness->value : 2.0;

    const Mask body = bodyMask(lat, detail::maskWhere(lat.size(), [&](std::size_t i) { return values[i] > 0.0f; }));
    AutomaticLabels out;
    out.lattice = lat;
    out.extent = torsoExtent(v, lat, body);
    std::vector<std::int32_t>& labels = out.labels;
    labels.assign(lat.size(), volume::kAirLabel);
    if (contrast == MrContrast::Unknown) {
        detail::forEachVoxel(lat.size(), [&](std::size_t i) {
            if (body[i]) labels[i] = soft;
        });
        const auto& w = v.metadata().mrWeighting;
        out.notes.push_back("MR intensity grid, not T1 (weighting: " +
            std::string(volume::mrWeightingName(w.value_or(volume::MrWeightingKind::Unknown))) +
            "): its contrast does not tell fat from muscle, so the body is labelled soft_tissue only; "
            "import a label map for more classes");
        return out;
    }
    const bool t1InMs = contrast == MrContrast::T1Ms;
    // Which voxels the fat | muscle rule reads: the whole body in torso slices;
    // elsewhere only the subcutaneous layer (a head's white matter is as bright
    // as fat on T1-weighted images, and lies deeper than the scalp and skull).
    const std::size_t stride = lat.strides()[std::size_t(lat.sliceAxis)];
    const auto slices = std::size_t(lat.dims[lat.sliceAxis]);
    const auto inTorso = [&](std::size_t i) { return out.extent.inTorso(int((i / stride) % slices)); };
    Mask read = body;
    if (!out.extent.all()) {
        Mask outside(body.size());
        detail::forEachVoxel(body.size(), [&](std::size_t i) { outside[i] = body[i] ? 0 : 1; });
        const std::vector<float> d2 = squaredDistance(lat, outside, Span::Volume);
        const auto r2 = float(kSubcutaneousMm * kSubcutaneousMm);
        detail::forEachVoxel(body.size(), [&](std::size_t i) { read[i] = body[i] && (inTorso(i) || d2[i] <= r2); });
    }
    std::vector<float> inside;
    for (std::size_t n = 0; n < values.size(); ++n) {
        if (read[n] && values[n] > 0.0f) inside.push_back(values[n]);
    }
    double split = 0.0;
    // Fluid first (the long tail would pull Otsu's split away from fat | muscle):
    // split once, take the non-fat class's median as muscle, cut the fluid, split again.
    if (!inside.empty()) split = otsuThreshold(inside);
    const auto isFat = [&](float x) { return t1InMs ? x <= split : x > split; };
    std::vector<float> lean;
    for (float x : inside) {
        if (!isFat(x)) lean.push_back(x);
    }
    const double muscleMedian = medianOf(lean);
    const auto isFluid = [&](float x) {
        return t1InMs ? x > kFluidFactor * muscleMedian : x < muscleMedian / kFluidFactor;
    };
    std::vector<float> solid;
    for (float x : inside) {
        if (!isFluid(x)) solid.push_back(x);
    }
    if (!solid.empty()) split = otsuThreshold(solid);
    detail::forEachVoxel(lat.size(), [&](std::size_t i) {
        if (!body[i]) return;
        const float x = values[i];
        // No signal inside the body (bone, gas in the gut), fluid, and what the rule
        // does not read are soft tissue: T1 cannot tell.
        if (x <= 0.0f || !read[i] || isFluid(x))
            labels[i] = soft;
        else if (isFat(x))
            labels[i] = fat;
        else
            labels[i] = inTorso(i) ? muscle : soft;
    });
    markSkin(lat, body, skinMm, skin, labels);
    std::string note = torsoNote(v, lat, out.extent, "MR fat | muscle split",
        "there fat is labelled only within " + std::to_string(int(kSubcutaneousMm)) +
            " mm of the skin (the scalp's; a brain's white matter is as bright), and the rest is "
            "soft_tissue, never muscle");
    if (!note.empty()) out.notes.push_back(std::move(note));
    return out;
}

} // namespace voxhap::segmentation
