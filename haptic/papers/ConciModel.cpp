// SPDX-License-Identifier: Apache-2.0
/// @file ConciModel.cpp
/// @brief Fitting and evaluation of the Conci model (physics.md §3).

#include "haptic/papers/ConciModel.h"

#include "core/Errors.h"

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

const std::vector<ConciSeed>& conciSeeds()
{
    // physics.md §3.2, [C-ui] seed data; punctures of flavum and epidural/dura are depth-triggered (step 2).
    static const std::vector<ConciSeed> kSeeds{
        {"skin", 6.0372, 10.8, false, true},
        {"fat", 1.974, 2.8, false, true},
        {"muscle", 4.354, 1.9, false, true},
        {"interspinous_ligament", 7.467, 18.0, false, true},
        {"ligamentum_flavum", 12.133, 7.4, true, true},
        {"epidural_dura", 2.437, 8.6, true, false},
    };
    return kSeeds;
}

double tipSlopeMultiplier(TipType tip)
{
    switch (tip) { // physics.md §3.3 [chosen, calibrate]: coned 1.00, bevel 0.85, triangular 0.70
    case TipType::Coned:
        return 1.0;
    case TipType::Bevel:
        return 0.85;
    case TipType::Triangular:
        return 0.70;
    }
    return 1.0;
}

double conciBmiScale(double bmi)
{
    if (!std::isfinite(bmi) || bmi < 10.0 || bmi > 80.0) throw ValueError("Conci model: BMI outside 10..80 kg/m^2");
    constexpr double kTableSedMm = 40.9; // sum of the table's layers above the epidural space (§3.3)
    return 10.0 * (2.52 + 0.11 * bmi) / kTableSedMm;
}

std::vector<ConciLayer> fitConci(const std::vector<ConciSeed>& seeds, double scale, TipType tip, double nextPunctureN)
{
    if (!(scale > 0.0) || !std::isfinite(scale)) throw ValueError("Conci model: scale must be positive");
    std::vector<ConciLayer> out;
    double z = 0.0, entry = 0.0; // R_in: the previous plateau, 0 for the skin (step 1)
    const double m = tipSlopeMultiplier(tip);
    for (std::size_t i = 0; i < seeds.size(); ++i) {
        const ConciSeed& s = seeds[i];
        ConciLayer l;
        l.name = s.name;
        l.zStartMm = z;
        l.thicknessMm = s.thicknessMm * (s.scalesWithBmi ? scale : 1.0);
        l.punctureDepthMm = s.depthTriggered ? l.thicknessMm : 0.6 * l.thicknessMm; // step 2
        const double rise = s.punctureForceN - entry;
        l.ce0 = entry; // step 3
        l.ce1 = m * rise / (2.0 * l.punctureDepthMm);
        l.ce2 = m * rise / (2.0 * l.punctureDepthMm * l.punctureDepthMm);
        l.sfMaxN = l.ce0 + l.ce1 * l.punctureDepthMm + l.ce2 * l.punctureDepthMm * l.punctureDepthMm;
        const double next = i + 1 < seeds.size() ? seeds[i + 1].punctureForceN : nextPunctureN;
        l.cp0 = 0.5 * std::min(s.punctureForceN, next); // step 4
        l.tfN = l.sfMaxN - l.cp0;
        out.push_back(l);
        entry = l.cp0;
        z += l.thicknessMm;
    }
    return out;
}

ConciModel::ConciModel(std::vector<ConciLayer> layers) : mLayers(std::move(layers)), mPunctured(mLayers.size(), 0) { }

void ConciModel::reset() noexcept { std::fill(mPunctured.begin(), mPunctured.end(), 0); }

ConciModel::Output ConciModel::update(double z) noexcept
{
    Output o;
    if (!std::isfinite(z) || z < 0.0 || mLayers.empty()) return o;
    std::size_t i = 0;
    while (i + 1 < mLayers.size() && z >= mLayers[i + 1].zStartMm) ++i;
    const ConciLayer& l = mLayers[i];
    if (z >= l.zStartMm + l.thicknessMm) return o; // past the table
    o.layer = int(i);
    // Reaching a layer punctures every layer before it ("or when the next tissue is reached").
    for (std::size_t j = 0; j < i; ++j) {
        if (!mPunctured[j]) {
            mPunctured[j] = 1;
            o.punctured = true;
        }
    }
    const double u = z - l.zStartMm;
    if (!mPunctured[i]) {
        const double elastic = l.ce0 + u * (l.ce1 + u * (l.ce2 + u * l.ce3));
        if (elastic < l.sfMaxN && u < l.punctureDepthMm) {
            o.forceN = elastic;
            return o;
        }
        mPunctured[i] = 1; // S_f,max reached: the force drops by T_f
        o.punctured = true;
    }
    const double w = std::max(0.0, u - l.punctureDepthMm); // Δdp: depth past the puncture
    o.forceN = l.cp0 + w * (l.cp1 + w * l.cp2);
    return o;
}

} // namespace voxhap::haptic
