// SPDX-License-Identifier: Apache-2.0
/// @file Scene.cpp
/// @brief Scene files: strict parsing (every error names the file and the field)
/// and the set-up of what a scene needs.

#include "haptic/scene/Scene.h"

#include "core/BoundedRead.h"
#include "core/Errors.h"
#include "core/Format.h"
#include "core/JsonFields.h"
#include "phantoms/Phantoms.h"
#include "volume/VolumeFile.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <system_error>

namespace voxhap::haptic {

extern const std::vector<std::pair<std::string, std::string>>& builtinSceneFiles(); // SceneBuiltin.cpp (generated)

namespace {

using Json = nlohmann::json;
using Fields = JsonFields;

DeviceLimits parseDevice(Fields& top)
{
    if (!top.has("device")) return DeviceLimits{};
    if (top.raw("device").is_string()) {
        try {
            return deviceLimits(top.raw("device").get<std::string>());
        } catch (const ValueError& e) {
            top.fail("device", e.what());
        }
    }
    DeviceLimits l;
    // d refuses unknown fields as it goes out of scope: before l is returned, which clang
    // would otherwise never free (a destructor throwing after the return, CWG 2176).
    {
        Fields d = top.sub("device");
        l.name = d.string("name", "custom");
        // Ranges: docs/scenes.md. The largest grounded haptic devices render tens of
        // newtons (Virtuose 6D: 31 N peak) and a few N/mm; 100 N and 20 N/mm leave margin.
        l.maxForceN = d.within("max_force_N", l.maxForceN, 0.0, 100.0, "N", true);
        l.maxContinuousForceN = d.within("max_continuous_force_N", l.maxContinuousForceN, 0.0, 100.0, "N", true);
        l.maxStiffnessNPerMm = d.within("max_stiffness_N_per_mm", l.maxStiffnessNPerMm, 0.0, 20.0, "N/mm", true);
        l.maxDampingNsPerMm = d.within("max_damping_Ns_per_mm", l.maxDampingNsPerMm, 0.0, 1.0, "N·s/mm", true);
        // Kyung's F_G = −m·g (physics.md §1.1): a handle of a few hundred grams; 10 kg leaves margin.
        l.handleMassKg = d.within("handle_mass_kg", l.handleMassKg, 0.0, 10.0, "kg");
        if (d.has("down")) {
            const Json& v = d.raw("down");
            const auto bad = [&d] { d.fail("down", "must be a direction [x, y, z] (world LPS), finite and non-zero"); };
            if (!v.is_array() || v.size() != 3) bad();
            double n2 = 0.0;
            for (std::size_t i = 0; i < 3; ++i) {
                if (!v[i].is_number() || !std::isfinite(v[i].get<double>())) bad();
                l.down[i] = v[i].get<double>();
                n2 += l.down[i] * l.down[i];
            }
            if (!(n2 > 0.0) || !std::isfinite(n2)) bad();
            for (double& c : l.down) c /= std::sqrt(n2);
        }
        d.string("source", "");
        // The I²t limiter (physics.md §6.3) holds the continuous force below the peak.
        if (l.maxContinuousForceN > l.maxForceN)
            d.fail("max_continuous_force_N", "must not exceed max_force_N (" + std::to_string(l.maxForceN) + " N)");
    }
    return l;
}

void parseTerms(Fields& top, ForceTerms& t)
{
    t = ForceTerms{};
    if (!top.has("terms")) top.fail("terms", "missing: name the force terms the scene uses");
    Fields terms = top.sub("terms");
    t.tip = terms.term("tip");
    t.cutting = terms.term("cutting");
    t.viscous = terms.term("viscous");
    if (terms.term("karnopp")) {
        Fields k = terms.sub("karnopp");
        t.karnoppDeltaVMmPerS = k.within("delta_v_mm_per_s", 1.0, 0.0, 100.0, "mm/s");
        t.keepDirectionN = k.within("keep_direction_N", 0.0, 0.0, 10.0, "N");
    }
    if ((t.damping.on = terms.term("damping")) && terms.isObject("damping")) {
        Fields d = terms.sub("damping");
        t.damping.capN = d.within("cap_N", t.damping.capN, 0.0, 100.0, "N", true);
        t.damping.referenceSpeedMmPerS =
            d.within("reference_speed_mm_per_s", t.damping.referenceSpeedMmPerS, 0.0, 5000.0, "mm/s", true);
    }
    if ((t.bone.on = terms.term("bone")) && terms.isObject("bone")) {
        Fields b = terms.sub("bone");
        t.bone.transient = b.boolean("transient", true);
        t.bone.params.amplitudeNsPerM =
            b.within("amplitude_Ns_per_m", t.bone.params.amplitudeNsPerM, 0.0, 1e4, "N·s/m");
        t.bone.params.durationS =
            b.within("duration_ms", t.bone.params.durationS * 1e3, 0.0, 1000.0, "ms", true) * 1e-3;
        t.bone.params.frequencyHz = b.within("frequency_Hz", t.bone.params.frequencyHz, 0.0, 1e4, "Hz", true);
        t.bone.params.peakClampN = b.within("peak_clamp_N", t.bone.params.peakClampN, 0.0, 100.0, "N");
    }
    if ((t.pivot.on = terms.term("pivot")) && terms.isObject("pivot")) {
        Fields p = terms.sub("pivot");
        PivotParams& q = t.pivot.params;
        q.kappa1NPerMm2 = p.within("kappa1_N_per_mm2", q.kappa1NPerMm2, 0.0, 1.0, "N/mm²");
        q.kappa2NPerMm2 = p.within("kappa2_N_per_mm2", q.kappa2NPerMm2, 0.0, 1.0, "N/mm²", true);
        q.tauS = p.within("tau_ms", q.tauS * 1e3, 0.0, 10000.0, "ms", true) * 1e-3;
        q.hubDistanceMm = p.within("hub_distance_mm", q.hubDistanceMm, 0.0, 500.0, "mm", true);
        q.layerThicknessMm = p.within("layer_thickness_mm", q.layerThicknessMm, 0.0, 100.0, "mm", true);
        q.maxForceN = p.within("cap_N", q.maxForceN, 0.0, 100.0, "N");
    }
    if ((t.lock.on = terms.term("lock")) && terms.isObject("lock")) {
        t.lock.stiffnessNPerMm = terms.sub("lock").within("stiffness_N_per_mm", 0.0, 0.0, 20.0, "N/mm");
    }
    if ((t.lor.on = terms.term("lor")) && terms.isObject("lor")) {
        Fields l = terms.sub("lor");
        t.lor.params.timeConstantS =
            l.within("time_constant_ms", t.lor.params.timeConstantS * 1e3, 0.0, 10000.0, "ms", true) * 1e-3;
        t.lor.params.blockedForceN = l.within("blocked_force_N", t.lor.params.blockedForceN, 0.0, 100.0, "N");
    }
    if ((t.boneTexture.on = terms.term("bone_texture")) && terms.isObject("bone_texture")) {
        // [LP] bone texture −c·sgn(v) (physics.md §4); c is [chosen] 0.3 N there.
        t.boneTexture.cN = terms.sub("bone_texture").within("c_N", t.boneTexture.cN, 0.0, 10.0, "N");
    }
    if ((t.palpation.on = terms.term("palpation")) && terms.isObject("palpation")) {
        Fields p = terms.sub("palpation");
        PalpationParams& q = t.palpation.params;
        q.entryRadiusMm = p.within("entry_radius_mm", q.entryRadiusMm, 0.0, 100.0, "mm", true);
        q.modulusKPa = p.within("modulus_kPa", q.modulusKPa, 0.0, 1e4, "kPa", true);
        q.contactAreaMm2 = p.within("contact_area_mm2", q.contactAreaMm2, 0.0, 1e4, "mm²", true);
        q.minStiffnessNPerMm = p.within("min_stiffness_N_per_mm", q.minStiffnessNPerMm, 0.0, 20.0, "N/mm", true);
        q.maxStiffnessNPerMm = p.within("max_stiffness_N_per_mm", q.maxStiffnessNPerMm, 0.0, 20.0, "N/mm");
        q.frictionSoft = p.within("friction_soft", q.frictionSoft, 0.0, 10.0, "");
        q.frictionBone = p.within("friction_bone", q.frictionBone, 0.0, 10.0, "");
        q.radiusMm = p.within("radius_mm", q.radiusMm, 0.0, 500.0, "mm", true);
        q.aboveMm = p.within("above_mm", q.aboveMm, 0.0, 500.0, "mm");
        q.reachMm = p.within("reach_mm", q.reachMm, 0.0, 1000.0, "mm", true);
        q.gridMm = p.within("grid_mm", q.gridMm, 0.0, 10.0, "mm");
        q.skinHu = p.within("skin_HU", q.skinHu, -1024.0, 3071.0, "HU");
        q.boneHu = p.within("bone_HU", q.boneHu, -1024.0, 3071.0, "HU");
        const std::string source = p.string("source", "auto");
        if (source == "auto")
            q.source = SkinSource::Auto;
        else if (source == "labels")
            q.source = SkinSource::Labels;
        else if (source == "hu")
            q.source = SkinSource::Hu;
        else
            p.fail("source", "must be \"auto\", \"labels\" or \"hu\"");
    }
    if ((t.guidance.on = terms.term("guidance")) && terms.isObject("guidance")) {
        Fields g = terms.sub("guidance");
        GuidanceParams& q = t.guidance.params;
        q.stiffnessNPerMm = g.within("stiffness_N_per_mm", q.stiffnessNPerMm, 0.0, 20.0, "N/mm");
        q.maxForceN = g.within("max_force_N", q.maxForceN, 0.0, 100.0, "N");
        q.captureRadiusMm = g.within("capture_radius_mm", q.captureRadiusMm, 0.0, 500.0, "mm");
        q.fadeOutS = g.within("fade_out_s", q.fadeOutS, 0.0, 1e6, "s");
    }
    if ((t.bending.on = terms.term("bending")) && terms.isObject("bending"))
        (void)terms.sub("bending"); // no parameters yet
    // §9.5: the beam's foundation holds the shaft where the pivot correction did; the
    // lock's straight line is one a bent shaft leaves.
    if (t.bending.on && t.lock.on)
        terms.fail("bending", "cannot run beside \"lock\", which ties the needle to a straight line");
    if (t.bending.on && t.pivot.on) terms.fail("bending", "replaces the pivot correction: turn \"pivot\" off");
    t.critical = terms.term("critical");
    if (terms.has("coupling_N_per_mm"))
        t.couplingNPerMm = terms.within("coupling_N_per_mm", 0.0, 0.0, 20.0, "N/mm", true);
}

/// The needle's bending keys (physics.md §9.1): material, E, wall, stylet, bevel.
void parseNeedleBending(Fields& n, Needle& needle)
{
    if (n.has("material")) {
        try {
            needle.material = parseNeedleMaterial(n.string("material", ""));
        } catch (const ValueError& e) {
            n.fail("material", e.what());
        }
    }
    // Steels and nickel–titanium lie near 40–210 GPa; 1000 GPa (diamond's order) leaves margin.
    if (const auto e = n.optWithin("youngs_modulus_GPa", 0.0, 1000.0, "GPa", true)) needle.youngsModulusMPa = *e * 1e3;
    if (n.has("inner_diameter_mm")) {
        const double id = n.number("inner_diameter_mm", 0.0);
        const double od = needle.outerDiameterMm();
        if (!(id < od))
            n.fail("inner_diameter_mm",
                "must be below the outer diameter (" + fixed(od, 3) + " mm for " + std::to_string(needle.gauge) +
                    " G; got " + fixed(id, 3) + ")");
        needle.innerDiameterGivenMm = id;
    }
    needle.stylet = n.boolean("stylet", needle.stylet);
    const double angle = n.number("bevel_angle_deg", needle.bevelAngleDeg);
    if (!(angle > 0.0 && angle < 90.0))
        n.fail("bevel_angle_deg", "must be in (0, 90) deg (got " + fixed(angle, 3) + ")");
    needle.bevelAngleDeg = angle;
    needle.bevelOrientationDeg = n.within("bevel_orientation_deg", needle.bevelOrientationDeg, -360.0, 360.0, "deg");
}

void parseOverrides(Fields& top, const std::string& origin, LayerRecipe& r)
{
    if (!top.has("overrides")) return;
    const Json& all = top.raw("overrides");
    if (!all.is_object()) top.fail("overrides", "must be an object of tissue names");
    for (const auto& [name, v] : all.items()) {
        Fields f(v, origin, "overrides." + name);
        TissueOverride to;
        to.punctureForceN = f.optWithin("puncture_force_N", 0.0, 100.0, "N");
        to.cuttingForceN = f.optWithin("cutting_force_N", 0.0, 100.0, "N");
        to.tentDepthMm = f.optWithin("tent_depth_mm", 0.0, 100.0, "mm", true);
        to.elasticityNPerMm = f.optWithin("elasticity_N_per_mm", 0.0, 100.0, "N/mm");
        f.string("source", "");
        r.overrides[name] = to;
    }
}

/// The scene's "success" block (Procedure.h), else the model's procedure's rule.
SuccessCriteria parseSuccess(Fields& top, LayerModel model)
{
    SuccessCriteria c;
    c.rule = model == LayerModel::Kyung       ? SuccessRule::ReachTarget
        : model == LayerModel::LumbarPuncture ? SuccessRule::ReachCsf
                                              : SuccessRule::DuraIntact;
    if (!top.has("success")) return c;
    Fields f = top.sub("success");
    if (f.has("rule")) {
        try {
            c.rule = parseSuccessRule(f.string("rule", ""));
        } catch (const ValueError& e) {
            f.fail("rule", e.what());
        }
    }
    if (f.has("radius_mm") && c.rule != SuccessRule::ReachTarget)
        f.fail("radius_mm", "applies to the reach_target rule only");
    c.radiusMm = f.within("radius_mm", c.radiusMm, 0.0, 100.0, "mm", true);
    f.string("source", "");
    return c;
}

/// "assessment": {"<metric>": {"min": a, "max": b, "source": "..."}, ...}. The metric
/// names are checked by assessment/ (which knows metrics.json); here the ranges.
void parseAssessment(Fields& top, const std::string& origin, std::vector<MetricRange>& out)
{
    if (!top.has("assessment")) return;
    const Json& all = top.raw("assessment");
    if (!all.is_object()) top.fail("assessment", "must be an object of metric names");
    for (const auto& [name, v] : all.items()) {
        Fields f(v, origin, "assessment." + name);
        MetricRange r;
        r.metric = name;
        // Any finite bound: metrics carry their own units (docs/reference.md "Assessment").
        r.min = f.optWithin("min", -1e9, 1e9, "");
        r.max = f.optWithin("max", -1e9, 1e9, "");
        r.source = f.string("source", "");
        if (!r.min && !r.max) f.fail("", "give min, max or both");
        if (r.min && r.max && *r.min > *r.max) f.fail("min", "must not exceed max");
        if (r.source.empty()) f.fail("source", "missing: say where the range comes from (a paper, or [chosen])");
        out.push_back(std::move(r));
    }
}

/// @p message with control characters escaped: names quoted from the file ("a\nb") stay on one line.
std::string oneLine(const std::string& message)
{
    std::string out;
    for (const char c : message) {
        if (c == '\n') {
            out += "\\n";
        } else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
            char hex[8];
            std::snprintf(hex, sizeof hex, "\\x%02x", unsigned(static_cast<unsigned char>(c)));
            out += hex;
        } else {
            out += c;
        }
    }
    return out;
}

Scene readScene(const std::string& text, const std::string& origin)
{
    const Json doc = Fields::parse(text, origin); // a syntax error, or a number beyond double (1e99999)
    Scene s;
    s.origin = origin;
    Fields top(doc, origin, "");
    if (top.string("schema", "") != "voxhap-scene/1") top.fail("schema", "must be \"voxhap-scene/1\"");
    s.name = top.string("name", "");
    if (s.name.empty()) top.fail("name", "missing");
    s.description = top.string("description", "");
    s.source = top.string("source", "");

    if (top.has("volume")) {
        Fields v = top.sub("volume");
        s.volume.phantom = v.string("phantom", "");
        s.volume.file = v.string("file", "");
        s.volume.preset = v.string("preset", s.volume.preset);
        s.volume.bmi = v.optWithin("bmi", 10.0, 80.0, "kg/m²");
        s.volume.spacingMm = v.within("spacing_mm", s.volume.spacingMm, 0.0, 10.0, "mm", true);
        if (s.volume.phantom.empty() == s.volume.file.empty()) v.fail("", "name exactly one of phantom and file");
    }
    if (top.has("path")) {
        Fields p = top.sub("path");
        if (p.has("entry")) s.entry = p.vec3("entry");
        if (p.has("target")) s.target = p.vec3("target");
        s.entryLandmark = p.string("entry_landmark", s.entryLandmark);
        s.targetLandmark = p.string("target_landmark", "");
    }
    try {
        s.recipe.model = parseLayerModel(top.string("model", ""));
    } catch (const ValueError& e) {
        top.fail("model", e.what());
    }
    const std::string layers = top.string("layers", "labels");
    if (layers != "labels" && layers != "table") top.fail("layers", "must be \"labels\" or \"table\"");
    s.fixedTable = layers == "table";
    if (top.has("tenting")) {
        s.recipe.tenting.clear();
        const Json& t = top.raw("tenting");
        if (!t.is_array()) top.fail("tenting", "must be a list of tissue names");
        for (const Json& n : t) {
            if (!n.is_string()) top.fail("tenting", "must be a list of tissue names");
            s.recipe.tenting.push_back(n.get<std::string>());
        }
    }
    // Kyung's skin tents only where the scene names it ([K01] §1.1: 20 mm skin deformation
    // before puncture); Sénac's default list is [S19]'s derma and dura.
    if (s.recipe.model == LayerModel::Kyung && !top.has("tenting")) s.recipe.tenting.clear();
    parseOverrides(top, origin, s.recipe);
    parseTerms(top, s.terms);
    // A uniform scale of the rendered tissue force: contrasts survive,
    // the device's I²t budget lasts. (0, 10]: a scale beyond 10 is a typo.
    s.terms.renderScale = top.within("force_scale", 1.0, 0.0, 10.0, "", true);
    s.success = parseSuccess(top, s.recipe.model);
    if (top.has("needle")) {
        Fields n = top.sub("needle");
        const auto gauge = [&n](const char* key, int def) { // 20.5 would read as 20, and 1e10 fits no int
            const double g = n.number(key, def, true);
            if (g != std::floor(g) || g > 1e6) n.fail(key, "must be a whole gauge number (14 to 27)");
            return int(g); // the range is checked with the needle below
        };
        s.needle.gauge = gauge("gauge", s.needle.gauge);
        s.needle.referenceGauge = gauge("reference_gauge", s.needle.referenceGauge);
        s.needle.lengthMm = n.within("length_mm", s.needle.lengthMm, 0.0, 500.0, "mm", true);
        try {
            s.needle.tip = parseTipType(n.string("tip", tipTypeName(s.needle.tip)));
            (void)s.needle.forceScale(); // validates both gauges
        } catch (const ValueError& e) {
            n.fail("", e.what());
        }
        parseNeedleBending(n, s.needle);
    }
    s.recipe.tip = s.needle.tip;
    s.recipe.forceScale = s.needle.forceScale();
    if (!top.has("device")) {
        s.defaulted.push_back("no \"device\" given: the \"touch\" preset (3.3 N peak, 0.88 N continuous)");
    }
    s.device = parseDevice(top);
    if (top.has("insertion")) {
        Fields i = top.sub("insertion");
        // A hand moves a needle at most a few m/s (Session.h kMaxHandSpeedMmPerS); the
        // servo rate's range is the CLI's --rate.
        s.speedMmPerS = i.within("speed_mm_per_s", s.speedMmPerS, 0.0, 5000.0, "mm/s", true);
        s.rateHz = i.within("rate_Hz", s.rateHz, 1.0, 1e6, "Hz");
        s.approachMm = i.within("approach_mm", s.approachMm, 0.0, 500.0, "mm");
        s.depthMm = i.optWithin("depth_mm", 0.0, 1000.0, "mm", true);
    } else {
        s.defaulted.push_back("no \"insertion\" given: 10 mm/s at 1000 Hz from 5 mm outside the entry, to the target");
    }
    parseAssessment(top, origin, s.assessment);
    if (s.recipe.model == LayerModel::Kyung && s.fixedTable)
        top.fail("layers", "the kyung model reads voxels: use \"labels\"");
    return s;
}

} // namespace

Scene parseScene(const std::string& text, const std::string& origin)
{
    try {
        return Fields::guarded(origin, [&] { return readScene(text, origin); });
    } catch (const ValueError& e) {
        throw ValueError(oneLine(e.what())); // a refusal is one line, whatever names it quotes
    }
}

Scene loadScene(const std::string& nameOrPath)
{
    for (const auto& [name, text] : builtinSceneFiles()) {
        if (name == nameOrPath) return parseScene(text, "builtin:" + name);
    }
    std::error_code ec;
    if (!std::filesystem::exists(nameOrPath, ec)) {
        std::string names;
        for (const auto& n : builtinSceneNames()) names += (names.empty() ? "" : ", ") + n;
        throw IoError(nameOrPath + ": no such scene file or built-in scene (" + names + ")");
    }
    // A regular file within the size limit: not a FIFO, /dev/zero or a huge file.
    return parseScene(readBoundedFile(nameOrPath, "scene file"), nameOrPath);
}

std::vector<std::string> builtinSceneNames()
{
    std::vector<std::string> names;
    for (const auto& f : builtinSceneFiles()) names.push_back(f.first);
    return names;
}

std::shared_ptr<const volume::Volume> makeSourceVolume(const VolumeSource& s, const volume::TissueTable& table)
{
    if (!s.file.empty()) {
        requireRegularFile(s.file, "volume", /*allowDirectory=*/true); // not a FIFO or a device
        return std::make_shared<const volume::Volume>(volume::loadVolume(s.file));
    }
    volume::GridSpec grid;
    grid.spacing = Vec3d::Constant(s.spacingMm);
    // Any of the four phantoms with its default parameters; lumbar takes the preset and BMI.
    volume::PhantomSpec spec;
    spec.kind = s.phantom;
    spec.lumbar.preset = volume::parseLumbarPreset(s.preset);
    spec.lumbar.bmi = s.bmi;
    const volume::PhantomModel m = volume::phantomModel(spec, table);
    return std::make_shared<const volume::Volume>(volume::makePhantom(m, grid, table));
}

SceneInstance::SceneInstance(const Scene& scene, std::shared_ptr<const volume::Volume> vol,
    const volume::TissueTable& table, std::optional<Vec3d> entry, std::optional<Vec3d> target)
    : mScene(scene), mVolume(vol ? std::move(vol) : makeSourceVolume(scene.volume, table))
{
    const bool needLabels = !scene.fixedTable || scene.terms.critical || scene.terms.bending.on;
    if (needLabels && !mVolume->has(volume::Channel::Label)) {
        throw ValueError(scene.origin +
            ": the volume has no tissue labels, which this scene's layers and critical-structure "
            "rule read: give a labelled volume (a phantom, or a segmented scan)");
    }
    const auto pick = [&](std::optional<Vec3d> given, std::optional<Vec3d> fromScene, const std::string& mark,
                          const char* what) {
        if (given) return *given;
        if (fromScene) return *fromScene;
        if (auto p = mark.empty() ? std::nullopt : volume::phantomLandmark(*mVolume, mark)) return *p;
        throw ValueError(
            scene.origin + ": path." + what + ": not given, and the volume has no landmark '" + mark + "'");
    };
    mEntry = pick(entry, scene.entry, scene.entryLandmark, "entry");
    mTarget = pick(target, scene.target, scene.targetLandmark, "target");
    const Vec3d dir = mTarget - mEntry;
    if (!(dir.norm() > 1e-6)) throw ValueError(scene.origin + ": path: entry and target coincide");

    // Only the grids the named terms read (architecture.md "Sparse by default").
    if (scene.terms.damping.on || needLabels) {
        MaterialOptions mo;
        mo.needs.damping = scene.terms.damping.on;
        mo.needs.boneStiffness = false; // bone renders at the device's stiffness (§1.3)
        mo.device = scene.device;
        mo.tipAreaMm2 = scene.needle.tipAreaMm2();
        mField = std::make_unique<MaterialField>(*mVolume, table, mo);
    }
    // Palpation reads the skin and the bone beneath it across the path (Palpation.h).
    if (scene.terms.palpation.on) {
        try {
            mSkin = std::make_shared<const SkinMap>(
                *mVolume, table, mEntry, dir, scene.terms.palpation.params, scene.device.maxStiffnessNPerMm);
        } catch (const ValueError& e) {
            throw ValueError(scene.origin + ": terms." + e.what());
        }
    }
    if (scene.fixedTable) {
        mLayers = fixedLayers(scene.recipe, table, volume::parseLumbarPreset(scene.volume.preset), scene.volume.bmi);
    } else {
        const double reach = dir.norm() + scene.needle.lengthMm;
        mLayers = layersFromRuns(traceLabelRuns(*mField, mEntry, dir, reach), table, scene.recipe);
    }
}

std::unique_ptr<NeedleForceModel> SceneInstance::makeModel(const std::optional<GuideLine>& guide) const
{
    std::unique_ptr<ShaftIntegrator> integrator, locked;
    if (mField && (mScene.terms.damping.on || (mScene.terms.critical && mField->labels()))) {
        IntegratorOptions o;
        o.strategy = Strategy::ExactVoxel;
        o.trackLabels = mScene.terms.critical && mField->labels();
        integrator = makeIntegrator(*mField, o);
        if (mScene.terms.damping
                .on) { // the profile integrates β: after skin entry (architecture.md "Shaft integration")
            o.strategy = Strategy::Profile;
            o.profileMaxLengthMm = std::max(o.profileMaxLengthMm, 2.0 * mScene.needle.lengthMm);
            locked = makeIntegrator(*mField, o);
        }
    }
    ForceTerms terms = mScene.terms;
    if (guide) terms.guidance.on = true; // a planned line turns guidance on, at the scene's parameters
    std::unique_ptr<Foundation> foundation;
    if (terms.bending.on) foundation = makeLabelFoundation(*mField); // §9.2: k per label
    return std::make_unique<NeedleForceModel>(ForceModelSetup{.layers = mLayers,
        .path = NeedlePath{mEntry, mTarget - mEntry},
        .terms = terms,
        .needle = mScene.needle,
        .device = mScene.device,
        .integrator = std::move(integrator),
        .field = mField.get(),
        .locked = std::move(locked),
        .skin = mSkin,
        .guide = guide,
        .foundation = std::move(foundation)});
}

} // namespace voxhap::haptic
