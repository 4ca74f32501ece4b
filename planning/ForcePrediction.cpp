// SPDX-License-Identifier: Apache-2.0
/// @file ForcePrediction.cpp
#include "planning/ForcePrediction.h"

#include "haptic/InsertionState.h"

#include <algorithm>
#include <cmath>

namespace voxhap::planning {

namespace {

/// The damping share of the model (NeedleForceModel::step, §1.2 and §6.2): what the
/// device renders as damping, the rest as friction at the reference speed, within the cap.
double dampingForce(const haptic::ForceTerms& t, const haptic::DeviceLimits& dev, double b, double v)
{
    if (!t.damping.on || v <= 0.0) return 0.0;
    b = std::max(0.0, b);
    const double rendered = std::min(b, dev.maxDampingNsPerMm);
    const double viscous = std::min(rendered * v, t.damping.capN);
    return viscous + std::clamp((b - rendered) * t.damping.referenceSpeedMmPerS, 0.0, t.damping.capN - viscous);
}

} // namespace

DampingLine::DampingLine(std::vector<DampingPiece> pieces) : mPieces(std::move(pieces))
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
    const auto it = std::upper_bound(mPieces.begin(), mPieces.end(), x, [](double v, const DampingPiece& p) { return v < p.startMm; });
    if (it == mPieces.begin()) return 0.0;
    const std::size_t k = std::size_t(it - mPieces.begin()) - 1;
    const DampingPiece& p = mPieces[k];
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

        double nonElastic = 0.0; // every term but the elastic stage
        const int current = tip.currentLayer();
        if (in.terms.cutting && current >= 0) {
            const auto& cur = layers[std::size_t(current)];
            nonElastic += tip.cuttingSumN;
            if (tip.pushLayer < 0 && tip.inLayer >= 0) nonElastic += layers[std::size_t(tip.inLayer)].plateauN(tip.plateauDepthMm);
            if (std::abs(v) >= in.terms.karnoppDeltaVMmPerS) nonElastic += cur.coulombN;
        }
        if (in.terms.viscous && current >= 0) nonElastic += tip.viscousNsPerMm * v;
        if (in.terms.damping.on && in.damping) {
            nonElastic += dampingForce(in.terms, in.device, in.damping->integral(std::max(0.0, d - L), d), v);
        }
        const bool critical = touchesCritical(d);

        // A tenting layer that popped since the last sample peaked at its puncture force
        // just before: record that peak, which a fixed depth step would otherwise miss.
        if (in.terms.tip) {
            for (const haptic::Event& e : events) {
                if (e.type != haptic::EventType::Pop || e.layer < 0) continue;
                const auto& l = layers[std::size_t(e.layer)];
                if (!l.tents) continue;
                const double fp = std::isfinite(l.punctureForceN) ? l.punctureForceN : l.elasticForceN(l.punctureDepthMm);
                add(d, critical ? 0.0 : fp + nonElastic);
            }
        }
        if (tip.boneLayer >= 0) { // §1.3 contact: the profile ends on the bone surface
            p.contactMm = std::min(d, layers[std::size_t(tip.boneLayer)].startMm);
            add(p.contactMm, critical ? 0.0 : nonElastic);
            break;
        }
        const double elastic = in.terms.tip && tip.pushLayer >= 0 ? layers[std::size_t(tip.pushLayer)].elasticForceN(tip.pushMm) : 0.0;
        add(d, critical ? 0.0 : elastic + nonElastic);
    }
    return p;
}

} // namespace voxhap::planning
