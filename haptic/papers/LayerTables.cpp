// SPDX-License-Identifier: Apache-2.0
/// @file LayerTables.cpp
/// @brief Layers from labels and from the papers' tables (physics.md §2.2, §2.3,
/// §3.2, §3.3, §4).

#include "haptic/papers/LayerTables.h"

#include "haptic/shaft/LabelTrace.h"

#include "core/Errors.h"
#include "haptic/papers/LumbarPunctureModel.h"
#include "haptic/papers/SenacModel.h"

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

LayerModel parseLayerModel(const std::string& name)
{
    if (name == "kyung") return LayerModel::Kyung;
    if (name == "senac") return LayerModel::Senac;
    if (name == "conci") return LayerModel::Conci;
    if (name == "lumbar-puncture") return LayerModel::LumbarPuncture;
    throw ValueError("unknown force model '" + name + "' (kyung, senac, conci, lumbar-puncture)");
}

const char* layerModelName(LayerModel m)
{
    switch (m) {
    case LayerModel::Kyung:
        return "kyung";
    case LayerModel::Senac:
        return "senac";
    case LayerModel::Conci:
        return "conci";
    case LayerModel::LumbarPuncture:
        return "lumbar-puncture";
    }
    return "?";
}

double lorResistance(LayerRole role)
{
    switch (role) {
    case LayerRole::Skin:
    case LayerRole::Ligament:
    case LayerRole::Dura:
    case LayerRole::Bone:
        return 1.0;
    case LayerRole::Epidural:
        return 0.05;
    case LayerRole::Csf:
    case LayerRole::Air:
        return 0.0;
    case LayerRole::Tissue:
    case LayerRole::Critical:
        return 0.3;
    }
    return 0.0;
}

namespace {

double value(const std::optional<volume::Quantity>& q) { return q ? q->value : 0.0; }

/// The parts every model shares: name, role, bounds, contact and plunger.
Layer baseLayer(const volume::Tissue& t, double start, double end)
{
    Layer l;
    l.name = t.name;
    l.label = t.id;
    l.role = t.id == 0 ? LayerRole::Air : roleFromName(t.name, t.rigid, t.critical);
    l.rigid = t.rigid;
    l.startMm = start;
    l.endMm = end;
    l.lorResistance = lorResistance(l.role);
    return l;
}

TissueOverride overrideOf(const volume::Tissue& t, const LayerRecipe& r)
{
    const auto ov = r.overrides.find(t.name);
    return ov == r.overrides.end() ? TissueOverride{} : ov->second;
}

/// §2.1 Eq. 4 with the §2.2 [chosen] a1, a2, on the tissues the recipe names: the
/// elastic stage a1·z + a2·z² up to the puncture force (Sénac's derma and dura;
/// Kyung's skin, which [K01] §1.1 deforms before it gives way).
void applyTenting(Layer& l, const volume::Tissue& t, const LayerRecipe& r)
{
    if (l.rigid || l.role == LayerRole::Air) return;
    if (std::find(r.tenting.begin(), r.tenting.end(), t.name) == r.tenting.end()) return;
    const TissueOverride o = overrideOf(t, r);
    const double fp = o.punctureForceN.value_or(value(t.punctureForce)) * r.forceScale;
    const double k = o.elasticityNPerMm.value_or(value(t.elasticity));
    if (!(fp > 0.0)) return;
    if (!o.tentDepthMm && !(k > 0.0)) {
        throw ValueError("senac layers: tissue '" + t.name + "' tents but has neither elasticity nor tent_depth_mm");
    }
    const double zp = o.tentDepthMm.value_or(fp / (2.0 * k));
    const PrePunctureStiffness s = PrePunctureStiffness::fromPuncture(fp, zp);
    l.tents = true;
    l.elastic = {0.0, s.a1NPerMm, s.a2NPerMm2, 0.0};
    l.punctureForceN = fp;
}

/// §2.1 Eq. 1, 3–4: tenting where the recipe says, cutting everywhere, and shaft
/// friction (Okamura's third term, which [S19] left out) as the tissue table's viscous b.
void applySenac(Layer& l, const volume::Tissue& t, const LayerRecipe& r)
{
    if (l.rigid || l.role == LayerRole::Air) return;
    const TissueOverride o = overrideOf(t, r);
    l.cuttingForceN = o.cuttingForceN.value_or(value(t.cuttingForce)) * r.forceScale;
    l.viscousNsPerMm2 = value(t.frictionViscous);
    applyTenting(l, t, r);
}

/// §4: f_tip = −k·x within each layer (x from the layer's start, so the layer "pops"
/// at its end), viscous b·v·l and Coulomb C. The tip's forces, k·x and C, scale with
/// the needle's diameter, @p scale = d/d_ref (§3.3, Needle.h); the shaft's viscous
/// b·v·l is Sénac's shaft friction, which the tissue table gives unscaled.
void applyLumbarPuncture(Layer& l, double k, double b, double c, double scale)
{
    if (l.rigid) return;
    l.viscousNsPerMm2 = b;
    l.coulombN = c * scale;
    if (k > 0.0) {
        l.tents = true;
        l.elastic = {0.0, k * scale, 0.0, 0.0};
        l.punctureDepthMm = l.thicknessMm();
    }
}

/// §3.1: the fitted elastic stage, S_f,max / u_p puncture and the plastic plateau.
void applyConci(Layer& l, const ConciLayer& c)
{
    l.tents = true;
    l.elastic = {c.ce0, c.ce1, c.ce2, c.ce3};
    l.punctureForceN = c.sfMaxN;
    l.punctureDepthMm = c.punctureDepthMm;
    l.plateau = {c.cp0, c.cp1, c.cp2};
}

bool depthTriggered(LayerRole r, const std::string& name)
{
    return r == LayerRole::Epidural || r == LayerRole::Dura || name == "ligamentum_flavum";
}

std::vector<Layer> conciFromLayers(
    std::vector<Layer> layers, const std::vector<const volume::Tissue*>& tissues, const LayerRecipe& r)
{
    std::vector<ConciSeed> seeds;
    std::vector<std::size_t> which;
    double nextPuncture = kConciBonePunctureN;
    for (std::size_t i = 0; i < layers.size(); ++i) {
        const Layer& l = layers[i];
        if (l.role == LayerRole::Air || l.role == LayerRole::Critical) continue;
        if (l.rigid) { // the bone's puncture force closes the last plateau (§3.2 step 3)
            if (tissues[i]->punctureForce) nextPuncture = tissues[i]->punctureForce->value * r.forceScale;
            break;
        }
        // A tissue without a puncture force (soft_tissue, a lesion of an imported
        // segmentation) takes the default of LayerTables.h instead of stopping the scene.
        const double p = tissues[i]->punctureForce ? tissues[i]->punctureForce->value : kConciDefaultPunctureN;
        if (!(p > 0.0)) continue; // a fluid (CSF: 0 N) has no elastic stage to fit: entered at once, no plateau
        seeds.push_back({l.name, p * r.forceScale, l.thicknessMm(), depthTriggered(l.role, l.name), true});
        which.push_back(i);
    }
    if (seeds.empty()) return layers;
    const std::vector<ConciLayer> fit = fitConci(seeds, 1.0, r.tip, nextPuncture);
    for (std::size_t k = 0; k < fit.size(); ++k) applyConci(layers[which[k]], fit[k]);
    return layers;
}

} // namespace

std::vector<Layer> layersFromRuns(
    const std::vector<LabelRun>& runs, const volume::TissueTable& table, const LayerRecipe& r)
{
    std::vector<Layer> layers;
    std::vector<const volume::Tissue*> tissues;
    for (const LabelRun& run : runs) {
        const volume::Tissue* t = table.find(run.label);
        if (!t)
            throw ValueError("layers: label " + std::to_string(run.label) + " on the path is not in the tissue table");
        Layer l = baseLayer(*t, run.startMm, run.endMm);
        if (r.model == LayerModel::Senac) applySenac(l, *t, r);
        if (r.model == LayerModel::Kyung) applyTenting(l, *t, r); // [K01] §1.1: only the named tissues
        if (r.model == LayerModel::LumbarPuncture) {
            applyLumbarPuncture(
                l, value(t->elasticity), value(t->frictionViscous), value(t->frictionCoulomb), r.forceScale);
        }
        layers.push_back(std::move(l));
        tissues.push_back(t);
    }
    if (r.model == LayerModel::Conci) return conciFromLayers(std::move(layers), tissues, r);
    return layers;
}

std::vector<Layer> fixedLayers(
    const LayerRecipe& r, const volume::TissueTable& table, volume::LumbarPreset preset, std::optional<double> bmi)
{
    std::vector<Layer> layers;
    switch (r.model) {
    case LayerModel::Kyung:
        throw ValueError("the kyung model reads voxels: it has no fixed layer table");
    case LayerModel::LumbarPuncture: {
        double start = -5.0; // [LP] Table I starts 5 mm out of the skin
        for (const LpLayer& row : lpTable()) {
            Layer l;
            l.name = row.name;
            l.role = roleFromName(row.name, false, false);
            l.startMm = start;
            l.endMm = row.endMm - 5.0;
            l.lorResistance = lorResistance(l.role);
            // N/m → N/mm, N·s/m² → N·s/mm²; k and C at the needle's gauge (§3.3 d/d_ref)
            applyLumbarPuncture(l, row.kNPerM * 1e-3, row.bNsPerM2 * 1e-6, row.cN, r.forceScale);
            start = l.endMm;
            layers.push_back(std::move(l));
        }
        return layers;
    }
    case LayerModel::Conci: {
        const double scale = bmi ? conciBmiScale(*bmi) : 1.0;
        // Every force of the fit is linear in the seeds' puncture forces: scaling them by
        // the needle's d/d_ref (§3.3, Needle.h) scales the whole profile.
        std::vector<ConciSeed> seeds = conciSeeds();
        for (ConciSeed& sd : seeds) sd.punctureForceN *= r.forceScale;
        for (const ConciLayer& c : fitConci(seeds, scale, r.tip, kConciBonePunctureN * r.forceScale)) {
            Layer l;
            l.name = c.name;
            l.role = roleFromName(c.name, false, false);
            l.startMm = c.zStartMm;
            l.endMm = c.zStartMm + c.thicknessMm;
            l.lorResistance = lorResistance(l.role);
            applyConci(l, c);
            layers.push_back(std::move(l));
        }
        return layers;
    }
    case LayerModel::Senac: {
        volume::LumbarParams p;
        p.preset = preset;
        p.bmi = bmi;
        const volume::LumbarLayout lay = volume::lumbarLayout(p, table);
        const std::pair<const char*, double> rows[] = {{"skin", lay.skin}, {"fat", lay.fat},
            {"supraspinous_ligament", lay.supraspinous}, {"interspinous_ligament", lay.interspinous},
            {"ligamentum_flavum", lay.flavum}, {"epidural_space", lay.epidural}, {"dura", lay.dura}, {"csf", lay.csf}};
        double start = 0.0;
        for (const auto& [name, thickness] : rows) {
            const volume::Tissue& t = table.at(name);
            Layer l = baseLayer(t, start, start + thickness);
            applySenac(l, t, r);
            start = l.endMm;
            layers.push_back(std::move(l));
        }
        return layers;
    }
    }
    return layers;
}

} // namespace voxhap::haptic
