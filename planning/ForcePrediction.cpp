// SPDX-License-Identifier: Apache-2.0
/// @file ForcePrediction.cpp
#include "planning/ForcePrediction.h"

#include "haptic/force/InsertionState.h"
#include "haptic/force/NeedleForceModel.h"

#include <algorithm>
#include <cmath>

namespace voxhap::planning {

DampingLine::DampingLine(std::vector<haptic::DampingPiece> pieces) : mPieces(std::move(pieces))
{
    mBefore.reserve(mPieces.size());
    double sum = 0.0;
    for (const auto& p : mPieces) {
        mBefore.push_back(sum);
        sum += p.beta * (p.endMm - p.startMm);
    }
}

double DampingLine::to(double x) const
{
    // The last piece starting before x.
    const auto it = std::upper_bound(
        mPieces.begin(), mPieces.end(), x, [](double v, const haptic::DampingPiece& p) { return v < p.startMm; });
    if (it == mPieces.begin()) return 0.0;
    const std::size_t k = std::size_t(it - mPieces.begin()) - 1;
    const haptic::DampingPiece& p = mPieces[k];
    return mBefore[k] + p.beta * (std::min(x, p.endMm) - p.startMm);
}

ForceProfile predictForce(const ForceModelInputs& in, double lengthMm)
{
    ForceProfile p;
    if (!in.layers) return p;
    const std::vector<haptic::Layer>& layers = *in.layers;
    const double v = in.speedMmPerS, L = in.needle.lengthMm;
    haptic::InsertionState state(layers);
    haptic::EventBuffer events;

    // The model's rule (NeedleForceModel::touchingCritical: a punctured critical
    // layer, or a critical voxel anywhere on the shaft) on a straight path with
    // a label field: a critical layer overlapping the shaft [d - L, d].
    const auto touchesCritical = [&](double d) {
        if (!in.terms.critical) return false;
        for (const auto& l : layers) {
            if (l.role == haptic::LayerRole::Critical && l.startMm < d && l.endMm > d - L) return true;
        }
        return false;
    };
    const auto add = [&](double d, double f) {
        p.samples.push_back({d, f});
        if (f > p.peakN) p.peakN = f, p.peakDepthMm = d;
    };

    const double step = std::max(in.stepMm, 1e-3);
    const int n = int(std::ceil(lengthMm / step - 1e-9));
    for (int k = 0; k <= n; ++k) {
        const double d = std::min(lengthMm, k * step);
        events.clear();
        state.update(d, d / std::max(v, 1e-9), L, events);
        const haptic::TipState& tip = state.tip();

        // Every term but the elastic stage, as the servo model computes them.
        double nonElastic = haptic::tipSlipForceN(in.terms, tip, layers, v);
        if (in.terms.viscous && tip.currentLayer() >= 0) nonElastic += tip.viscousNsPerMm * v; // §4 Eq. 3
        if (in.terms.damping.on && in.damping) {
            const haptic::DampingSplit split =
                haptic::splitDamping(in.terms.damping, in.device, in.damping->integral(std::max(0.0, d - L), d), v);
            nonElastic += split.viscousN + split.frictionN;
        }
        const bool critical = touchesCritical(d);

        // A tenting layer that popped since the last sample peaked at its puncture force
        // just before: record that peak, which a fixed depth step would otherwise miss.
        if (in.terms.tip) {
            for (const haptic::Event& e : events) {
                if (e.type != haptic::EventType::Pop || e.layer < 0) continue;
                const auto& l = layers[std::size_t(e.layer)];
                if (!l.tents) continue;
                const double fp =
                    std::isfinite(l.punctureForceN) ? l.punctureForceN : l.elasticForceN(l.punctureDepthMm);
                add(d, critical ? 0.0 : fp + nonElastic);
            }
        }
        if (tip.boneLayer >= 0) { // §1.3 contact: the profile ends on the bone surface
            p.contactMm = std::min(d, layers[std::size_t(tip.boneLayer)].startMm);
            add(p.contactMm, critical ? 0.0 : nonElastic);
            break;
        }
        const double elastic =
            in.terms.tip && tip.pushLayer >= 0 ? layers[std::size_t(tip.pushLayer)].elasticForceN(tip.pushMm) : 0.0;
        add(d, critical ? 0.0 : elastic + nonElastic);
    }
    return p;
}

} // namespace voxhap::planning
