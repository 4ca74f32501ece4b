// SPDX-License-Identifier: Apache-2.0
/// @file FuzzScene.cpp
/// @brief libFuzzer target: the scene parser (haptic/scene/Scene.h). Besides
/// "no crash" and the refusal convention, an accepted scene is checked against
/// the JSON read here independently: only known fields, every number that was
/// given is the one in the scene (with its unit conversion), finite and of the
/// sign the field allows, and strings, switches and lists as written.

#include "FuzzInput.h"

#include "haptic/scene/Scene.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <functional>
#include <initializer_list>
#include <set>
#include <string>
#include <vector>

namespace {

using Json = nlohmann::json;
using voxhap::fuzz::finding;
using voxhap::haptic::Scene;

/// The value at @p path, or null when absent or null (the parser's "absent").
const Json* at(const Json& doc, std::initializer_list<const char*> path)
{
    const Json* j = &doc;
    for (const char* k : path) {
        if (!j->is_object() || !j->contains(k)) return nullptr;
        j = &j->at(k);
    }
    return j->is_null() ? nullptr : j;
}

std::string name(std::initializer_list<const char*> path)
{
    std::string s;
    for (const char* k : path) s += (s.empty() ? "" : ".") + std::string(k);
    return s;
}

/// Refused keys: an accepted object holds only @p known ones.
void onlyKnown(const Json* j, const std::string& where, const std::set<std::string>& known)
{
    if (!j || !j->is_object()) return;
    for (const auto& [k, v] : j->items()) {
        if (!known.count(k)) finding(where + ": unknown field '" + k + "' accepted");
    }
}

enum class Sign {
    Positive,
    NonNegative,
    Any
};

void checkSign(double x, Sign sign, const std::string& what)
{
    if (!std::isfinite(x)) finding(what + ": not finite");
    if (sign == Sign::Positive && !(x > 0.0)) finding(what + ": not positive");
    if (sign == Sign::NonNegative && !(x >= 0.0)) finding(what + ": negative");
}

/// A number the scene was given: read as written (times @p scale), finite and of its sign.
void number(const Json& doc, std::initializer_list<const char*> path, double got, Sign sign, double scale = 1.0)
{
    const Json* j = at(doc, path);
    if (!j) return;
    const std::string what = name(path);
    if (!j->is_number()) finding(what + ": a " + std::string(j->type_name()) + " accepted as a number");
    checkSign(j->get<double>(), sign, what + " as written");
    checkSign(got, sign, what + " as read");
    if (got != j->get<double>() * scale) finding(what + ": read differs from the file");
}

void string(const Json& doc, std::initializer_list<const char*> path, const std::string& got)
{
    if (const Json* j = at(doc, path)) {
        if (!j->is_string() || j->get<std::string>() != got) finding(name(path) + ": read differs from the file");
    }
}

/// A force term: absent off, false off, true or an object on.
void term(const Json& doc, const char* key, bool got)
{
    const Json* j = at(doc, {"terms", key});
    if (!j) {
        if (got) finding(std::string("terms.") + key + ": on although absent");
        return;
    }
    if (!(j->is_boolean() || j->is_object())) finding(std::string("terms.") + key + ": accepted as a term");
    if (got != (j->is_object() || j->get<bool>())) finding(std::string("terms.") + key + ": read differs");
}

void checkScene(const Json& doc, const Scene& s)
{
    using voxhap::haptic::LayerModel;
    if (!doc.is_object()) finding("a scene that is not an object");
    onlyKnown(&doc, "top",
        {"schema", "name", "description", "source", "volume", "path", "model", "layers", "tenting", "overrides",
            "terms", "needle", "device", "insertion", "force_scale", "success", "assessment"});
    if (!at(doc, {"schema"}) || *at(doc, {"schema"}) != "voxhap-scene/1")
        finding("schema: accepted without voxhap-scene/1");
    if (s.name.empty()) finding("name: empty");
    string(doc, {"name"}, s.name);
    string(doc, {"description"}, s.description);
    string(doc, {"source"}, s.source);

    // volume: exactly one of phantom and file
    onlyKnown(at(doc, {"volume"}), "volume", {"phantom", "file", "preset", "bmi", "spacing_mm"});
    if (at(doc, {"volume"}) && s.volume.phantom.empty() == s.volume.file.empty())
        finding("volume: not exactly one of phantom and file");
    string(doc, {"volume", "phantom"}, s.volume.phantom);
    string(doc, {"volume", "file"}, s.volume.file);
    string(doc, {"volume", "preset"}, s.volume.preset);
    if (at(doc, {"volume", "bmi"}) && !s.volume.bmi) finding("volume.bmi: given but not read");
    if (s.volume.bmi) number(doc, {"volume", "bmi"}, *s.volume.bmi, Sign::Positive);
    number(doc, {"volume", "spacing_mm"}, s.volume.spacingMm, Sign::Positive);

    onlyKnown(at(doc, {"path"}), "path", {"entry", "target", "entry_landmark", "target_landmark"});
    for (const auto& [key, got] : {std::pair{"entry", s.entry}, std::pair{"target", s.target}}) {
        const Json* j = at(doc, {"path", key});
        if (bool(j) != got.has_value()) finding(std::string("path.") + key + ": given and read disagree");
        if (!j) continue;
        if (!j->is_array() || j->size() != 3) finding(std::string("path.") + key + ": not [x, y, z]");
        for (int i = 0; i < 3; ++i) {
            const Json& c = (*j)[std::size_t(i)];
            if (!c.is_number() || c.get<double>() != (*got)[i] || !std::isfinite((*got)[i]))
                finding(std::string("path.") + key + ": read differs from the file");
        }
    }
    string(doc, {"path", "entry_landmark"}, s.entryLandmark);
    string(doc, {"path", "target_landmark"}, s.targetLandmark);

    const std::vector<std::pair<std::string, LayerModel>> models = {{"kyung", LayerModel::Kyung},
        {"senac", LayerModel::Senac}, {"conci", LayerModel::Conci}, {"lumbar-puncture", LayerModel::LumbarPuncture}};
    const Json* model = at(doc, {"model"});
    bool modelNamed = false;
    for (const auto& [n, m] : models) modelNamed |= model && *model == n && s.recipe.model == m;
    if (!modelNamed) finding("model: not one of the four, or read as another");
    const Json* layers = at(doc, {"layers"});
    if (s.fixedTable != (layers && *layers == "table")) finding("layers: read differs from the file");
    if (s.fixedTable && s.recipe.model == LayerModel::Kyung) finding("layers: a table for the kyung model");
    if (const Json* t = at(doc, {"tenting"}); t && Json(s.recipe.tenting) != *t) finding("tenting: read differs");
    if (!at(doc, {"tenting"}) && s.recipe.model == LayerModel::Kyung && !s.recipe.tenting.empty())
        finding("tenting: a kyung scene tents what it did not name");

    // force_scale and success
    number(doc, {"force_scale"}, s.terms.renderScale, Sign::Positive);
    onlyKnown(at(doc, {"success"}), "success", {"rule", "radius_mm", "source"});
    string(doc, {"success", "rule"}, voxhap::haptic::successRuleName(s.success.rule));
    if (at(doc, {"success", "radius_mm"}) && s.success.rule != voxhap::haptic::SuccessRule::ReachTarget)
        finding("success.radius_mm: accepted with a rule other than reach_target");
    number(doc, {"success", "radius_mm"}, s.success.radiusMm, Sign::Positive);

    if (const Json* o = at(doc, {"overrides"})) {
        if (!o->is_object() || o->size() != s.recipe.overrides.size()) finding("overrides: not one per tissue");
        for (auto it = o->begin(); it != o->end(); ++it) {
            const std::string tissue = it.key();
            const Json& v = it.value();
            onlyKnown(&v, "overrides." + tissue,
                {"puncture_force_N", "cutting_force_N", "tent_depth_mm", "elasticity_N_per_mm", "source"});
            const auto found = s.recipe.overrides.find(tissue);
            if (found == s.recipe.overrides.end()) finding("overrides." + tissue + ": lost");
            const auto& to = found->second;
            const auto check = [&](const char* key, const std::optional<double>& got, Sign sign) {
                if (bool(at(v, {key})) != got.has_value()) finding("overrides." + tissue + "." + key + ": lost");
                if (got) number(v, {key}, *got, sign);
            };
            check("puncture_force_N", to.punctureForceN, Sign::NonNegative);
            check("cutting_force_N", to.cuttingForceN, Sign::NonNegative);
            check("tent_depth_mm", to.tentDepthMm, Sign::Positive);
            check("elasticity_N_per_mm", to.elasticityNPerMm, Sign::NonNegative);
        }
    }

    // terms: required; each sub-object read only when the term is on
    const auto& t = s.terms;
    if (!at(doc, {"terms"})) finding("terms: accepted without");
    onlyKnown(at(doc, {"terms"}), "terms",
        {"tip", "cutting", "viscous", "karnopp", "damping", "bone", "pivot", "lock", "lor", "critical",
            "coupling_N_per_mm", "bone_texture", "palpation", "guidance", "bending"});
    term(doc, "bending", t.bending.on);
    onlyKnown(at(doc, {"terms", "bending"}), "terms.bending", {});
    if (t.bending.on && (t.lock.on || t.pivot.on)) finding("terms.bending: accepted beside the lock or the pivot");
    term(doc, "bone_texture", t.boneTexture.on);
    onlyKnown(at(doc, {"terms", "bone_texture"}), "terms.bone_texture", {"c_N"});
    number(doc, {"terms", "bone_texture", "c_N"}, t.boneTexture.cN, Sign::NonNegative);
    term(doc, "tip", t.tip);
    term(doc, "cutting", t.cutting);
    term(doc, "viscous", t.viscous);
    term(doc, "damping", t.damping.on);
    term(doc, "bone", t.bone.on);
    term(doc, "pivot", t.pivot.on);
    term(doc, "lock", t.lock.on);
    term(doc, "lor", t.lor.on);
    term(doc, "critical", t.critical);
    onlyKnown(at(doc, {"terms", "karnopp"}), "terms.karnopp", {"delta_v_mm_per_s", "keep_direction_N"});
    number(doc, {"terms", "karnopp", "delta_v_mm_per_s"}, t.karnoppDeltaVMmPerS, Sign::NonNegative);
    number(doc, {"terms", "karnopp", "keep_direction_N"}, t.keepDirectionN, Sign::NonNegative);
    onlyKnown(at(doc, {"terms", "damping"}), "terms.damping", {"cap_N", "reference_speed_mm_per_s"});
    number(doc, {"terms", "damping", "cap_N"}, t.damping.capN, Sign::Positive);
    number(doc, {"terms", "damping", "reference_speed_mm_per_s"}, t.damping.referenceSpeedMmPerS, Sign::Positive);
    onlyKnown(at(doc, {"terms", "bone"}), "terms.bone",
        {"transient", "amplitude_Ns_per_m", "duration_ms", "frequency_Hz", "peak_clamp_N"});
    if (const Json* b = at(doc, {"terms", "bone", "transient"}); b && *b != t.bone.transient)
        finding("terms.bone.transient: read differs");
    number(doc, {"terms", "bone", "amplitude_Ns_per_m"}, t.bone.params.amplitudeNsPerM, Sign::NonNegative);
    number(doc, {"terms", "bone", "duration_ms"}, t.bone.params.durationS, Sign::Positive, 1e-3);
    number(doc, {"terms", "bone", "frequency_Hz"}, t.bone.params.frequencyHz, Sign::Positive);
    number(doc, {"terms", "bone", "peak_clamp_N"}, t.bone.params.peakClampN, Sign::NonNegative);
    onlyKnown(at(doc, {"terms", "pivot"}), "terms.pivot",
        {"kappa1_N_per_mm2", "kappa2_N_per_mm2", "tau_ms", "hub_distance_mm", "layer_thickness_mm", "cap_N"});
    const auto& p = t.pivot.params;
    number(doc, {"terms", "pivot", "kappa1_N_per_mm2"}, p.kappa1NPerMm2, Sign::NonNegative);
    number(doc, {"terms", "pivot", "kappa2_N_per_mm2"}, p.kappa2NPerMm2, Sign::Positive);
    number(doc, {"terms", "pivot", "tau_ms"}, p.tauS, Sign::Positive, 1e-3);
    number(doc, {"terms", "pivot", "hub_distance_mm"}, p.hubDistanceMm, Sign::Positive);
    number(doc, {"terms", "pivot", "layer_thickness_mm"}, p.layerThicknessMm, Sign::Positive);
    number(doc, {"terms", "pivot", "cap_N"}, p.maxForceN, Sign::NonNegative);
    onlyKnown(at(doc, {"terms", "lock"}), "terms.lock", {"stiffness_N_per_mm"});
    number(doc, {"terms", "lock", "stiffness_N_per_mm"}, t.lock.stiffnessNPerMm, Sign::NonNegative);
    onlyKnown(at(doc, {"terms", "lor"}), "terms.lor", {"time_constant_ms", "blocked_force_N"});
    number(doc, {"terms", "lor", "time_constant_ms"}, t.lor.params.timeConstantS, Sign::Positive, 1e-3);
    number(doc, {"terms", "lor", "blocked_force_N"}, t.lor.params.blockedForceN, Sign::NonNegative);
    number(doc, {"terms", "coupling_N_per_mm"}, t.couplingNPerMm, Sign::Positive);

    // needle: whole gauges from 14 to 27, the recipe follows it
    onlyKnown(at(doc, {"needle"}), "needle",
        {"gauge", "reference_gauge", "length_mm", "tip", "material", "youngs_modulus_GPa", "inner_diameter_mm",
            "stylet", "bevel_angle_deg", "bevel_orientation_deg"});
    if (at(doc, {"needle", "youngs_modulus_GPa"}))
        number(doc, {"needle", "youngs_modulus_GPa"}, s.needle.youngsModulusMPa, Sign::Positive, 1e3);
    if (at(doc, {"needle", "inner_diameter_mm"})) {
        number(doc, {"needle", "inner_diameter_mm"}, s.needle.innerDiameterGivenMm, Sign::NonNegative);
        if (!(s.needle.innerDiameterMm() < s.needle.outerDiameterMm())) finding("needle: ID not below the OD accepted");
    }
    number(doc, {"needle", "bevel_angle_deg"}, s.needle.bevelAngleDeg, Sign::Positive);
    if (!(s.needle.bevelAngleDeg > 0.0 && s.needle.bevelAngleDeg < 90.0))
        finding("needle.bevel_angle_deg: outside (0, 90) accepted");
    number(doc, {"needle", "bevel_orientation_deg"}, s.needle.bevelOrientationDeg, Sign::Any);
    string(doc, {"needle", "material"}, voxhap::haptic::needleMaterialName(s.needle.material));
    if (const Json* b = at(doc, {"needle", "stylet"}); b && *b != s.needle.stylet)
        finding("needle.stylet: read differs");
    for (const int g : {s.needle.gauge, s.needle.referenceGauge}) {
        if (g < 14 || g > 27) finding("needle: gauge " + std::to_string(g) + " outside 14..27");
    }
    number(doc, {"needle", "gauge"}, s.needle.gauge, Sign::Positive);
    number(doc, {"needle", "reference_gauge"}, s.needle.referenceGauge, Sign::Positive);
    number(doc, {"needle", "length_mm"}, s.needle.lengthMm, Sign::Positive);
    string(doc, {"needle", "tip"}, voxhap::haptic::tipTypeName(s.needle.tip));
    checkSign(s.needle.forceScale(), Sign::Positive, "needle force scale");
    if (s.recipe.forceScale != s.needle.forceScale() || s.recipe.tip != s.needle.tip)
        finding("needle: the layer recipe does not follow the needle");

    // device: a preset's name or an object of limits
    if (const Json* d = at(doc, {"device"}); d && d->is_string()) {
        if (s.device.name != d->get<std::string>()) finding("device: not the preset named");
    } else if (d) {
        onlyKnown(d, "device",
            {"name", "max_force_N", "max_continuous_force_N", "max_stiffness_N_per_mm", "max_damping_Ns_per_mm",
                "handle_mass_kg", "down", "source"});
        number(doc, {"device", "handle_mass_kg"}, s.device.handleMassKg, Sign::NonNegative);
        double n2 = 0.0;
        for (const double c : s.device.down) n2 += c * c;
        if (!(std::abs(n2 - 1.0) < 1e-12)) finding("device.down: not a unit direction");
        string(doc, {"device", "name"}, s.device.name);
        number(doc, {"device", "max_force_N"}, s.device.maxForceN, Sign::Positive);
        number(doc, {"device", "max_continuous_force_N"}, s.device.maxContinuousForceN, Sign::Positive);
        number(doc, {"device", "max_stiffness_N_per_mm"}, s.device.maxStiffnessNPerMm, Sign::Positive);
        number(doc, {"device", "max_damping_Ns_per_mm"}, s.device.maxDampingNsPerMm, Sign::Positive);
    }

    onlyKnown(at(doc, {"insertion"}), "insertion", {"speed_mm_per_s", "rate_Hz", "approach_mm", "depth_mm"});
    number(doc, {"insertion", "speed_mm_per_s"}, s.speedMmPerS, Sign::Positive);
    number(doc, {"insertion", "rate_Hz"}, s.rateHz, Sign::Positive);
    number(doc, {"insertion", "approach_mm"}, s.approachMm, Sign::NonNegative);
    if (bool(at(doc, {"insertion", "depth_mm"})) != s.depthMm.has_value()) finding("insertion.depth_mm: lost");
    if (s.depthMm) number(doc, {"insertion", "depth_mm"}, *s.depthMm, Sign::Positive);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    return voxhap::fuzz::parseText(data, size, "fuzz.json", [](std::string_view text, const std::string& file) {
        const Scene s = voxhap::haptic::parseScene(std::string(text), file);
        // Accepted: the JSON parses, and read independently it agrees with the scene.
        checkScene(Json::parse(text), s);
        if (s.origin != file) finding("origin: not the file");
    });
}
