// SPDX-License-Identifier: Apache-2.0
/// @file ClosedForm.cpp
/// @brief The analytic regression phantoms of physics.md §7 as references of a
/// regression case: R1 (layered damping slab, tilted or not) and R5 (sphere in a
/// slab), for a model whose only axial term is Kyung's voxel damping (§1.2 Eq. 5);
/// R2 (the [LP] stack) and R3 (the Conci profile) for their scenes' fixed tables;
/// R4 (the Sénac nested boxes) for the Sénac scenes on the lumbar phantom.

#include "regress/CaseRunner.h"

#include "phantoms/Phantoms.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <set>

namespace voxhap::regress {

namespace {

// Why a case has no closed form, where several rules share the reason.
const char* const kScripted = "a scripted insertion (the closed forms are at constant speed)";
const char* const kNoSpeed = "no constant-speed straight insertion";
const char* const kGauge = "a needle gauge other than the reference gauge (§3.3's d/d_ref scaling)";

/// The material field stores β as float (a FloatGrid, MaterialField.h): each β
/// the run integrates is the double of §5.4 rounded to the nearest float, half
/// an ulp, 2⁻²⁴ relative. ∫β is a sum of non-negative terms, so its relative
/// error, and the force's, stays within the same bound.
constexpr double kFloatBeta = 0x1p-24;

/// A value of the record, else of the current inputs.
struct Lookup {
    const Inputs& recorded;
    const Inputs& current;
    const InputValue* find(const std::string& key) const
    {
        if (auto it = recorded.find(key); it != recorded.end()) return &it->second;
        if (auto it = current.find(key); it != current.end()) return &it->second;
        return nullptr;
    }
    std::optional<double> number(const std::string& key) const
    {
        const InputValue* v = find(key);
        return v ? v->number : std::nullopt;
    }
    std::string text(const std::string& key) const
    {
        const InputValue* v = find(key);
        return v ? v->text : std::string();
    }
};

std::optional<Vec3d> vecOf(const std::string& text)
{
    const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
    if (!j.is_array() || j.size() != 3) return std::nullopt;
    return Vec3d(j[0].get<double>(), j[1].get<double>(), j[2].get<double>());
}

/// Length of [a, b] inside [lo, hi].
double overlap(double a, double b, double lo, double hi) { return std::max(0.0, std::min(b, hi) - std::max(a, lo)); }

/// The recorded BMI of a lumbar phantom: a run records it as text ("none" without one).
std::optional<double> recordedBmi(const Lookup& in)
{
    if (auto bmi = in.number("phantom.bmi")) return bmi;
    const std::string text = in.text("phantom.bmi");
    char* end = nullptr;
    const double x = std::strtod(text.c_str(), &end);
    if (!text.empty() && end == text.c_str() + text.size()) return x;
    return std::nullopt;
}

/// A scene term is on in the record (else in the current inputs): recorded as its
/// value ("true", "false", "{}" for an object without parameters) or by its
/// parameters ("scene.terms.lor.time_constant_ms").
bool termOnIn(const Inputs& from, const std::string& name)
{
    const std::string key = "scene.terms." + name;
    for (auto it = from.lower_bound(key); it != from.end() && it->first.rfind(key, 0) == 0; ++it) {
        if (it->first == key) return it->second.text != "false";
        if (it->first[key.size()] == '.') return true;
    }
    return false;
}
bool termOn(const Lookup& in, const std::string& name)
{
    return termOnIn(in.recorded.empty() ? in.current : in.recorded, name);
}

/// Why the model is not voxel damping alone (§1.2), or empty when it is. An
/// allow-list: Eq. 5 damping, bone contact (R1 refuses rigid tissue on the path
/// itself), the pivot correction (lateral, §1.4) and the critical-structure rule
/// (R1 refuses critical tissue on the path). Any other term that is on, known
/// today or added later, takes the closed form away and is named. Judged on
/// the current scene: the terms the run had.
std::string notDampingOnly(const Inputs& current)
{
    static const std::set<std::string> kAllowed{"damping", "bone", "pivot", "critical"};
    bool damping = false;
    for (const auto& [key, v] : current) {
        if (key.rfind("scene.terms.", 0) != 0) continue;
        const std::string term = key.substr(12, key.find('.', 12) - 12);
        if (!termOnIn(current, term)) continue;
        if (!kAllowed.count(term)) return "term " + term;
        damping = damping || term == "damping";
    }
    return damping ? std::string() : "no damping term (R1 and R5 are Eq. 5 damping)";
}

/// physics.md §5.4: β of a tissue [N·s/mm²] from the values the run recorded,
/// computed here from the document, not by the material field under test. Fat
/// and muscle take Eq. 4, b = C1·exp(C2·T1), with the 1.5 T fit (C1 = 2464
/// N·s/m², C2 = 1.398e-3 /ms, T1 clamped to 290..856 ms): the regression
/// phantoms fill their t1 grid at 1.5 T (§7), which the material field reads;
/// every other tissue its table β. Empty when the record lacks the value.
std::optional<double> recordedBeta(const Lookup& in, const std::string& tissue)
{
    if (tissue == "fat" || tissue == "muscle") {
        const std::optional<double> t1 = in.number(tissue + ".t1_1.5T");
        if (!t1) return std::nullopt;
        return 2464.0 * std::exp(1.398e-3 * std::clamp(*t1, 290.0, 856.0)) * 1e-6; // N·s/m² → N·s/mm²
    }
    return in.number(tissue + ".damping");
}

/// physics.md §6.2, written here from the document (not haptic::splitDamping,
/// which is under test): with b = ∫β ds and the device's maximum damping b_dev,
/// the device renders min(b, b_dev)·v as viscosity, capped, and the rest of b at
/// the reference speed as friction, within what the cap leaves. Returns the sum.
double dampingForceN(double b, double v, double bDevice, double capN, double referenceSpeed)
{
    if (!(v > 0.0)) return 0.0;
    b = std::max(0.0, b);
    const double rendered = std::min(b, bDevice);
    const double viscous = std::min(rendered * v, capN);
    const double friction = std::clamp((b - rendered) * referenceSpeed, 0.0, capN - viscous);
    return viscous + friction;
}

/// Why a tissue of R1's slab or R5's sphere is not damping alone, or empty.
std::string notDampingTissue(const Lookup& in, const std::string& tissue)
{
    if (in.text(tissue + ".rigid") == "true") // bone: contact, not damping (§1.3)
        return "rigid tissue " + tissue + " on the path (contact, not damping)";
    if (in.text(tissue + ".critical") == "true" && termOnIn(in.current, "critical"))
        return "critical tissue " + tissue + " on the path (its force is zeroed)";
    return {};
}

/// physics.md §7 R2: the [LP] stack of §4, Table I reproduced from the document
/// (not from the code's table), at constant speed v > Δv:
/// f = k·x (x into the tip's layer) + C (the tip's layer) + Σ b_i·l_i·v.
ClosedFormCheck lumbarPunctureStack(const Case& c, const Lookup& in, const std::vector<Sample>& samples)
{
    struct Row {
        double endMm, kNPerM, bNsPerM2, cN;
    };
    static const Row kTable[] = {{5, 0, 0, 0}, {7, 330, 2.1, 0.3}, {14, 0, 1.0, 0.3}, {30, 550, 3.0, 0.5},
        {35, 980, 3.3, 0.6}, {48, 0, 1.6, 0.2}, {55, 2370, 0, 0}};
    const auto speed = in.current.find("case.speed_mm_per_s");
    if (!c.script.empty()) return ClosedFormCheck::none(kScripted);
    if (speed == in.current.end() || !speed->second.number) return ClosedFormCheck::none(kNoSpeed);
    const double v = *speed->second.number;
    const double deltaV = in.number("scene.terms.karnopp.delta_v_mm_per_s").value_or(1.0);
    const double rate = in.number("scene.insertion.rate_Hz").value_or(1000.0);
    if (!(v > deltaV)) return ClosedFormCheck::none("speed at or below Karnopp's Δv (R2 holds above it)");
    if (in.number("scene.needle.gauge").value_or(18.0) != in.number("scene.needle.reference_gauge").value_or(18.0))
        return ClosedFormCheck::none(kGauge); // §3.3's d/d_ref scaling of k and C: not part of R2
    // §4's bone texture −c·sgn(v) while the tip is in the bone row, when the scene has it
    // (c 0.3 N [chosen] unless the scene gives c_N).
    const double texture = termOn(in, "bone_texture") ? in.number("scene.terms.bone_texture.c_N").value_or(0.3) : 0.0;
    ClosedForm cf;
    cf.id = "R2";
    cf.rule = "physics.md §7 R2 ([LP] stack, §4 Table I" + std::string(texture > 0.0 ? ", bone texture" : "") + ")";
    for (const Sample& smp : samples) {
        const double depth = smp.depthMm + 5.0; // Table I starts 5 mm out of the skin
        double f = 0, start = 0, nearBoundary = 1e9;
        for (const Row& r : kTable) {
            nearBoundary = std::min(nearBoundary, std::abs(depth - r.endMm));
            const double l = overlap(5.0, depth, start, r.endMm); // shaft length in the layer [mm]
            f += r.bNsPerM2 * 1e-6 * l * v;                       // N·s/m² → N·s/mm²
            if (depth > start && depth <= r.endMm) f += r.kNPerM * 1e-3 * (depth - start) + r.cN;
            if (depth > start && depth <= r.endMm && &r == &kTable[std::size(kTable) - 1]) f += texture; // bone
            start = r.endMm;
        }
        if (depth <= 5.0) f = 0; // out of the skin
        cf.modelN.push_back(f);
        // Which side of a boundary a tick lands on is decided by rounding: a
        // tick's travel either side of one is not compared. Elsewhere R2's 1e-6 N.
        cf.toleranceN.push_back(nearBoundary <= 1.5 * v / rate ? std::numeric_limits<double>::infinity() : 1e-6);
    }
    return cf;
}

/// physics.md §7 R3: the Conci profile of §3, fitted from the [C-ui] seed data
/// of §3.2 (reproduced from the document, not from the code's table) by §3.2's
/// steps 1–4, the thicknesses scaled for the BMI (§3.3, the epidural space and
/// dura not) and the elastic slopes multiplied by the tip's factor (§3.3).
/// Within each layer (u from its start): Ce0 + Ce1·u + Ce2·u² up to the puncture
/// at u_p, then the plateau Cp0, a drop of exactly T_f.
ClosedFormCheck conciProfile(const Case& c, const Lookup& in, const std::vector<Sample>& samples)
{
    struct Seed {
        double punctureN, thicknessMm;
        bool depthTriggered, scales;
    };
    static const Seed kSeeds[] = {{6.0372, 10.8, false, true}, {1.974, 2.8, false, true}, {4.354, 1.9, false, true},
        {7.467, 18.0, false, true}, {12.133, 7.4, true, true}, {2.437, 8.6, true, false}};
    constexpr double kBonePunctureN = 8.0265; // §3.2, the bone row: P_{i+1} of the last plateau
    const auto speed = in.current.find("case.speed_mm_per_s");
    if (!c.script.empty()) return ClosedFormCheck::none(kScripted);
    if (speed == in.current.end() || !speed->second.number || !(*speed->second.number > 0))
        return ClosedFormCheck::none(kNoSpeed);
    const double v = *speed->second.number;
    const double rate = in.number("scene.insertion.rate_Hz").value_or(1000.0);
    if (in.number("scene.needle.gauge").value_or(18.0) != in.number("scene.needle.reference_gauge").value_or(18.0))
        return ClosedFormCheck::none(kGauge); // §3.3's d/d_ref scaling of every force: not part of R3
    const std::optional<double> bmi = recordedBmi(in);
    const double scale = bmi ? 10.0 * (2.52 + 0.11 * *bmi) / 40.9 : 1.0; // §3.3: s = SED/40.9 mm
    const std::string tip = in.text("scene.needle.tip");
    const double slope = tip == "bevel" ? 0.85 : tip == "triangular" ? 0.70 : 1.0; // §3.3

    struct Fit {
        double start, thickness, up, ce0, ce1, ce2, cp0;
    };
    std::vector<Fit> fit;
    double z = 0, entry = 0; // §3.2 step 1: R_in, 0 for the skin
    for (std::size_t i = 0; i < std::size(kSeeds); ++i) {
        const Seed& s = kSeeds[i];
        Fit f{};
        f.start = z;
        f.thickness = s.thicknessMm * (s.scales ? scale : 1.0);
        f.up = s.depthTriggered ? f.thickness : 0.6 * f.thickness; // step 2
        f.ce0 = entry;                                             // step 3
        f.ce1 = slope * (s.punctureN - entry) / (2 * f.up);
        f.ce2 = slope * (s.punctureN - entry) / (2 * f.up * f.up);
        const double next = i + 1 < std::size(kSeeds) ? kSeeds[i + 1].punctureN : kBonePunctureN;
        f.cp0 = 0.5 * std::min(s.punctureN, next); // step 4
        fit.push_back(f);
        entry = f.cp0;
        z += f.thickness;
    }
    const double tableEnd = z;
    // R3 states the profile exactly: only float rounding separates it from the
    // model (R4's 1e-12 relative, with a 1e-12 N floor for zero force).
    constexpr double kRounding = 1e-12;
    // Which side of a puncture a tick lands on is decided by rounding: a tick's
    // travel either side of a drop is not compared (as for R2).
    const double tick = 1.5 * v / rate;
    ClosedForm cf;
    cf.id = "R3";
    cf.rule = "physics.md §7 R3 (Conci profile, §3.2 fitted table" + std::string(bmi ? ", BMI-scaled" : "") + ")";
    for (const Sample& smp : samples) {
        const double d = smp.depthMm;
        double f = 0;
        bool compared = d < tableEnd - tick; // past the table §3 has no row (the bone row is contact)
        for (const Fit& l : fit) {
            if (std::abs(d - (l.start + l.up)) <= tick) compared = false;
            if (d < l.start || d >= l.start + l.thickness) continue;
            const double u = d - l.start;
            f = u < l.up ? l.ce0 + l.ce1 * u + l.ce2 * u * u : l.cp0;
        }
        cf.modelN.push_back(f);
        cf.toleranceN.push_back(
            compared ? kRounding * std::abs(f) + kRounding : std::numeric_limits<double>::infinity());
    }
    return cf;
}

/// What R4 reads of a run once the rule is known to apply.
struct SenacRun {
    double v = 0;      ///< insertion speed [mm/s]
    double rate = 0;   ///< servo rate [Hz]
    double needle = 0; ///< needle length [mm]
    double kc = 0;     ///< coupling stiffness k_c [N/mm]
    double tick = 0;   ///< travel per servo tick [mm]
    double h = 0;      ///< the grid's spacing along the midline [mm]
    bool tipOn = false, cuttingOn = false, frictionOn = false;
};

/// Where the rule applies: a constant-speed insertion down the midline of an
/// unturned lumbar phantom, a Sénac scene without other axial terms (Kyung's
/// damping §1.2, [LP]'s Coulomb C §4), forces at the gauge the table was measured with.
/// Returns why R4 does not apply, or "" with @p run filled.
std::string senacPreconditions(const Case& c, const Lookup& in, SenacRun& run)
{
    const auto currentText = [&](const std::string& key) {
        auto it = in.current.find(key);
        return it == in.current.end() ? std::string() : it->second.text;
    };
    const auto entry = vecOf(currentText("case.entry")), target = vecOf(currentText("case.target"));
    const auto rotation = vecOf(in.text("phantom.rotation_deg"));
    const auto spacing = vecOf(in.text("phantom.spacing_mm"));
    const std::optional<double> speed = in.number("case.speed_mm_per_s");
    if (!c.script.empty()) return kScripted;
    if (in.text("scene.layers") != "labels") return "the senac model on a fixed table";
    if (in.text("phantom.kind") != "lumbar")
        return "the senac model on the " + in.text("phantom.kind") + " phantom (R4: lumbar)";
    for (const char* term : {"damping", "karnopp"}) {
        if (termOn(in, term)) return "term " + std::string(term) + " beside the senac model";
    }
    if (!entry || !target || !rotation || !spacing || !speed) return kNoSpeed;
    if (entry->norm() != 0.0 || target->x() != 0.0 || target->z() != 0.0 || !(target->y() < 0.0))
        return "a path off the lumbar phantom's midline";
    if (rotation->norm() != 0.0) return "a rotated grid (R4: the phantom's own axes)";
    const double v = *speed;
    constexpr double kEpsilonMmPerS = 0.2; // §2.2 ε
    if (!(v > kEpsilonMmPerS))             // below ε Eq. 3 is 0, the proxy holds: no closed form
        return "speed at or below the senac model's ε (R4 holds above it)";
    if (in.number("scene.needle.gauge").value_or(18.0) != in.number("scene.needle.reference_gauge").value_or(18.0))
        return kGauge; // §3.3's d/d_ref scaling of every force: not part of R4
    run.v = v;
    run.rate = in.number("scene.insertion.rate_Hz").value_or(1000.0);
    run.needle = in.number("scene.needle.length_mm").value_or(90.0); // §3.3: the default needle, 90 mm
    run.kc = in.number("scene.terms.coupling_N_per_mm").value_or(0.0) > 0.0
        ? *in.number("scene.terms.coupling_N_per_mm")
        : in.number("device.max_stiffness_N_per_mm").value_or(0.0); // §6.2: k_c, else the device's maximum
    if (!(run.kc > 0.0) || !(run.rate > 0.0)) return "no coupling stiffness or servo rate";
    run.tick = v / run.rate; // travel per servo tick [mm]
    run.h = spacing->y();
    run.tipOn = termOn(in, "tip"), run.cuttingOn = termOn(in, "cutting"), run.frictionOn = termOn(in, "viscous");
    return {};
}

/// The lumbar midline's tissues from the skin down (§7 lumbar phantom).
const char* const kMidline[] = {"skin", "fat", "supraspinous_ligament", "interspinous_ligament", "ligamentum_flavum",
    "epidural_space", "dura", "csf"};
constexpr std::size_t kMidlineLayers = std::size(kMidline);

/// The midline layers' thicknesses (§7 lumbar phantom, §2.3 Table I, §3.3).
/// Returns why they are not known, or "".
std::string midlineThicknesses(const Lookup& in, double (&thickness)[kMidlineLayers])
{
    struct TableI {
        const char* preset;
        double dermaMm, epiduralMm;
    };
    static const TableI kTableI[] = {{"average", 10.0, 6.0}, {"overweight", 30.0, 4.0}, {"calcified", 10.0, 4.0}};
    const std::string preset = in.text("phantom.preset");
    const TableI* row = nullptr;
    for (const TableI& r : kTableI) {
        if (preset == r.preset) row = &r;
    }
    if (!row) return "lumbar preset '" + preset + "' has no [S19] Table I row";
    for (const int i : {0, 2, 3, 4, 6, 7}) {
        const auto t = in.number(std::string(kMidline[i]) + ".thickness");
        if (!t || !(*t > 0.0)) return std::string(kMidline[i]) + " has no thickness in the record";
        thickness[i] = *t;
    }
    thickness[1] = row->dermaMm - thickness[0];
    thickness[5] = row->epiduralMm;
    if (!(thickness[1] > 0.0)) return "no fat under the skin (derma thinner than the skin)";
    if (const auto bmi = recordedBmi(in)) {
        const double above = thickness[0] + thickness[1] + thickness[2] + thickness[3] + thickness[4];
        const double scale = 10.0 * (2.52 + 0.11 * *bmi) / above;
        for (int i = 0; i < 5; ++i) thickness[i] *= scale;
    }
    return {};
}

struct SenacLayer {
    std::string name;
    double top, bottom; // voxelised [mm]
    double cutN = 0, bNsPerMm2 = 0;
    bool tents = false;
    double a1 = 0, a2 = 0, zp = 0;
    double contact = 0, entry = 0; // where the tip meets it; where it is entered (its pop, if it tents)
    bool preloaded = false;        // its box is in a pop's preload: its own, or one that lands past its face
};

/// The layers on a grid of spacing @p h, with the scene's forces and tenting.
/// Returns why they cannot be, or "".
std::string senacLayers(
    const Lookup& in, const double (&thickness)[kMidlineLayers], double h, std::vector<SenacLayer>& layers)
{
    const auto face = [h](double depth) {
        const double x = depth / h - 0.5;
        const double n =
            std::abs(x - std::round(x)) < 1e-9 ? std::round(x) : std::ceil(x); // a centre on the plane: below
        return h * n;
    };
    std::vector<std::string> tenting{"skin", "dura"}; // without a list: [S19] tents the derma and the dura (§2.1)
    if (const std::string t = in.text("scene.tenting"); !t.empty()) {
        const nlohmann::json j = nlohmann::json::parse(t, nullptr, false);
        if (!j.is_array()) return "scene.tenting is not a list";
        tenting.clear();
        for (const auto& n : j) {
            if (n.is_string()) tenting.push_back(n.get<std::string>());
        }
    }
    double plane = 0;
    for (std::size_t i = 0; i < kMidlineLayers; ++i) {
        SenacLayer l;
        l.name = kMidline[i];
        l.top = face(plane);
        plane += thickness[i];
        l.bottom = face(plane);
        if (!(l.bottom > l.top)) continue; // thinner than a voxel: not on the grid
        const std::string t = l.name + ".", o = "scene.overrides." + l.name + ".";
        l.cutN = in.number(o + "cutting_force_N").value_or(in.number(t + "cutting_force").value_or(0.0));
        l.bNsPerMm2 = in.number(t + "friction_viscous").value_or(0.0);
        const double fp = in.number(o + "puncture_force_N").value_or(in.number(t + "puncture_force").value_or(0.0));
        const double k = in.number(o + "elasticity_N_per_mm").value_or(in.number(t + "elasticity").value_or(0.0));
        if (std::find(tenting.begin(), tenting.end(), l.name) != tenting.end() && fp > 0.0) {
            const auto zp = in.number(o + "tent_depth_mm");
            if (!zp && !(k > 0.0)) return l.name + " tents without a tent depth or elasticity";
            l.tents = true;
            l.zp = zp ? *zp : fp / (2.0 * k);
            l.a1 = fp / (2.0 * l.zp);
            l.a2 = fp / (2.0 * l.zp * l.zp);
        }
        layers.push_back(l);
    }
    if (layers.empty()) return "no layer thicker than a voxel";
    return {};
}

/// A box whose face lies within a tick of a pop: entered in the pop's tick or the next.
struct SenacTie {
    std::size_t layer, pop;
};

struct SenacEval {
    double f = 0;
    bool ramping = false;
    double slackN = 0; // a contact's uncertainty carried into the force
};

/// R4 states the profile exactly: float rounding only (10⁻¹² relative, with a
/// 10⁻¹² N floor for zero force).
constexpr double kSenacRounding = 1e-12;

/// The layers placed on the path, with the pops and the ticks rounding may
/// move, and R4 evaluated on them.
struct SenacModel {
    SenacRun run;
    std::vector<SenacLayer> layers;
    std::vector<double> pops;
    std::vector<SenacTie> ties;
    std::vector<bool> contactUncertain; ///< per layer: its stage may move by up to a tick
    double window = 0;                  ///< a tick's travel either side, as R2 and R3
    double compareEnd = 0;              ///< §7 gives the phantom no further along the midline

    SenacModel(const SenacRun& r, std::vector<SenacLayer> ls);
    /// R4 at depth @p d; preloaded[t]: the tie t's box is in its pop's preload.
    SenacEval evaluate(double d, const std::vector<bool>& preloaded) const;
    double tolerance(double d, const SenacEval& e) const;

private:
    /// Cutting (Eq. 3) through §6.2's proxy, with each layer's box entered at
    /// entered[i], in its pop's preload where inPreload[i]; @p ramping: below
    /// the sum of the boxes entered (the proxy sticks).
    double cuttingForce(
        double d, const std::vector<double>& entered, const std::vector<bool>& inPreload, bool& ramping) const;
};

SenacModel::SenacModel(const SenacRun& r, std::vector<SenacLayer> ls)
    : run(r), layers(std::move(ls)), contactUncertain(layers.size(), false), window(1.5 * r.tick),
      compareEnd(layers.back().bottom)
{
    // Where the tip meets and enters each layer; the pops.
    double lastPop = -std::numeric_limits<double>::infinity();
    for (SenacLayer& l : layers) {
        l.contact = std::max(l.top, lastPop);
        l.preloaded = l.tents || l.top <= lastPop;
        if (l.tents) {
            lastPop = l.contact + l.zp;
            pops.push_back(lastPop);
            l.entry = lastPop;
        } else {
            l.entry = l.contact;
        }
    }
    // Which tick a floating-point depth lands in is rounding: a box whose face lies
    // within a tick of a pop may be entered in the pop's tick (in the preload) or
    // the next (it ramps in). Both are R4 under §6.2; each segment between pops
    // takes the reading nearer the run. kPopTie: the pop's own slack.
    constexpr double kPopTie = 2e-9; // [mm] twice the state machine's 1e-9 mm "reached"
    for (std::size_t i = 0; i < layers.size(); ++i) {
        if (layers[i].tents) continue;
        for (std::size_t k = 0; k < pops.size(); ++k) {
            if (layers[i].top >= pops[k] - kPopTie && layers[i].top <= pops[k] + window) ties.push_back({i, k});
        }
    }
    // A tenting layer met within a tick of an earlier pop starts where that tick
    // lands: its stage moves by up to a tick.
    for (std::size_t i = 0; i < layers.size(); ++i) {
        for (const double p : pops) {
            if (layers[i].tents && p < layers[i].entry && layers[i].top >= p - kPopTie && layers[i].top <= p + window)
                contactUncertain[i] = true;
        }
    }
}

SenacEval SenacModel::evaluate(double d, const std::vector<bool>& preloaded) const
{
    SenacEval e;
    // The box entry of each layer under this reading.
    std::vector<double> entered(layers.size());
    std::vector<bool> inPreload(layers.size(), false);
    for (std::size_t i = 0; i < layers.size(); ++i) {
        entered[i] = layers[i].entry;
        inPreload[i] = layers[i].preloaded;
    }
    for (std::size_t t = 0; t < ties.size(); ++t) {
        const SenacLayer& l = layers[ties[t].layer];
        const double p = pops[ties[t].pop];
        entered[ties[t].layer] = preloaded[t] ? p : std::max(l.top, p);
        inPreload[ties[t].layer] = preloaded[t];
    }
    // Tenting stage and friction.
    double lengthB = 0; // Σ b·l over the shaft [N·s/mm]
    const double shaftStart = d - run.needle;
    for (std::size_t i = 0; i < layers.size(); ++i) {
        const SenacLayer& l = layers[i];
        if (l.tents && d >= l.contact && d < l.entry) {
            const double z = d - l.contact;
            if (run.tipOn) e.f += l.a1 * z + l.a2 * z * z;
            lengthB += l.bNsPerMm2 * (d - std::max(l.contact, shaftStart));
            if (contactUncertain[i])
                e.slackN += ((run.tipOn ? l.a1 + 2 * l.a2 * l.zp : 0.0) + run.v * l.bNsPerMm2) * run.tick;
        } else if (d >= entered[i]) {
            lengthB += l.bNsPerMm2 * overlap(shaftStart, d, l.top, l.bottom);
        }
    }
    if (run.frictionOn) e.f += run.v * lengthB;
    if (!run.cuttingOn) return e;
    e.f += cuttingForce(d, entered, inPreload, e.ramping);
    return e;
}

double SenacModel::cuttingForce(
    double d, const std::vector<double>& entered, const std::vector<bool>& inPreload, bool& ramping) const
{
    // The proxy: preloaded at the last pop, then sticking and slipping.
    double lastP = -std::numeric_limits<double>::infinity();
    for (const double p : pops) {
        if (p <= d) lastP = p;
    }
    const auto before = [&](std::size_t j) { // the sum just before box j is entered
        double sum = 0;
        for (std::size_t i = 0; i < layers.size(); ++i) {
            if (entered[i] < entered[j] || (entered[i] == entered[j] && inPreload[i] && !inPreload[j]))
                sum += layers[i].cutN;
        }
        return sum;
    };
    double total = 0, preload = 0;
    for (std::size_t i = 0; i < layers.size(); ++i) {
        if (entered[i] <= d) total += layers[i].cutN;
        if (entered[i] < lastP || (entered[i] == lastP && inPreload[i])) preload += layers[i].cutN;
    }
    double f = total;
    if (std::isfinite(lastP)) f = std::min(f, preload + run.kc * (d - lastP));
    for (std::size_t j = 0; j < layers.size(); ++j) {
        if (entered[j] > d || entered[j] < lastP || (entered[j] == lastP && inPreload[j]) || layers[j].cutN == 0.0)
            continue;
        f = std::min(f, before(j) + run.kc * (d - entered[j]));
    }
    ramping = f < total;
    return f;
}

double SenacModel::tolerance(double d, const SenacEval& e) const
{
    // Float rounding only (kSenacRounding). Within a ramp the sampled proxy starts
    // sticking at the last tick before the box's face, up to one tick before the
    // continuous form: k_c·v/rate more (0.004 N for 2 N/mm at 2 mm/s and 1 kHz).
    const double rampTick = run.kc * run.tick;
    if (d >= compareEnd) return std::numeric_limits<double>::infinity(); // beyond the phantom §7 describes
    for (std::size_t k = 0; k < pops.size(); ++k) {
        double w = window;
        for (std::size_t i = 0; i < layers.size(); ++i) {
            if (contactUncertain[i] && layers[i].entry == pops[k]) w += run.tick;
        }
        if (std::abs(d - pops[k]) <= w) return std::numeric_limits<double>::infinity(); // rounding picks the tick
    }
    return kSenacRounding * std::abs(e.f) + kSenacRounding + (e.ramping ? rampTick : 0.0) + e.slackN;
}

/// The readings of segment @p seg (between pops seg − 1 and seg) to choose
/// from: @p reading with a prefix of the ties of the pop that opens it in the
/// preload, the half-open reading (every tie in the preload) first.
std::vector<std::vector<bool>> segmentReadings(const SenacModel& m, std::size_t seg, const std::vector<bool>& reading)
{
    std::vector<std::size_t> mine; // the ties of the pop that opens this segment
    for (std::size_t t = 0; t < m.ties.size(); ++t) {
        if (seg > 0 && m.ties[t].pop == seg - 1) mine.push_back(t);
    }
    // The ties are entered in depth order: in the preload, a prefix of them.
    std::sort(mine.begin(), mine.end(),
        [&](std::size_t a, std::size_t b) { return m.layers[m.ties[a].layer].top < m.layers[m.ties[b].layer].top; });
    std::vector<std::vector<bool>> options;
    for (std::size_t k = mine.size() + 1; k-- > 0;) {
        std::vector<bool> r = reading;
        for (std::size_t q = 0; q < mine.size(); ++q) r[mine[q]] = q < k;
        options.push_back(r);
    }
    return options;
}

/// The readings differ only from the pop until the tied boxes' ramps end:
/// judged there by the largest |ΔF| (not against the tolerance, which a ramp
/// widens), on the samples in [lo, hi). The first of the best wins.
std::size_t nearestReading(const SenacModel& m, const std::vector<std::vector<bool>>& options,
    const std::vector<Sample>& samples, double lo, double hi)
{
    std::vector<double> worst(options.size(), 0.0);
    for (const Sample& smp : samples) {
        if (options.size() < 2 || smp.depthMm < lo || smp.depthMm >= hi) continue;
        std::vector<SenacEval> e;
        double fLo = std::numeric_limits<double>::infinity(), fHi = -fLo;
        for (const auto& r : options) {
            e.push_back(m.evaluate(smp.depthMm, r));
            fLo = std::min(fLo, e.back().f), fHi = std::max(fHi, e.back().f);
        }
        if (!(fHi - fLo > kSenacRounding * (std::abs(fHi) + 1))) continue;
        if (!std::isfinite(m.tolerance(smp.depthMm, e[0]))) continue;
        for (std::size_t q = 0; q < options.size(); ++q) worst[q] = std::max(worst[q], std::abs(smp.modelN - e[q].f));
    }
    std::size_t best = 0;
    for (std::size_t q = 1; q < options.size(); ++q) {
        if (worst[q] < worst[best]) best = q;
    }
    return best;
}

/// R4's pops (the skin at 10 mm in the shipped scenes): the first tick at or
/// past each, so within a tick's travel.
void expectPops(ClosedForm& cf, const SenacModel& m, double lastDepth)
{
    cf.eventsUpToMm = std::min(m.compareEnd, lastDepth);
    bool clear = true;
    for (const double p : m.pops) clear = clear && std::abs(p - cf.eventsUpToMm) > m.window;
    if (clear) {
        for (const double p : m.pops) {
            if (p < cf.eventsUpToMm) cf.events.push_back({"pop", p, m.window});
        }
    } else {
        cf.eventsUpToMm = 0; // a pop within a tick of the end: rounding decides whether it happens
    }
}

/// physics.md §7 R4: the Sénac model of §2.1 with the constants of §2.2, on the
/// lumbar phantom's midline, rendered as §6.2 renders it. Derived here from the
/// documents and the recorded values, not from the code's layer table:
/// - the layers (§7's lumbar phantom): skin and ligaments from the table's
///   thicknesses, fat = derma − skin and the epidural space from [S19] Table I
///   (§2.3), dura and CSF from the table; for a BMI everything above the
///   epidural space scaled by SED/(its sum), SED = 10·(2.52 + 0.11·BMI) mm
///   (§3.3). A voxel takes the tissue at its centre and faces lie on multiples
///   of the spacing h (§7): each plane at depth D moves to the face h·⌈D/h − ½⌉;
/// - tenting (Eq. 4): each tenting tissue of the scene is pushed from where the
///   tip meets it (its face, or the last pop if that lies deeper): a1·z + a2·z²,
///   a1 = F_p/(2z_p), a2 = F_p/(2z_p²) (§2.2), z_p the scene's tent depth, else
///   F_p/(2k); it pops at z_p, and the layers below are pushed ahead until then;
/// - cutting (Eq. 3): the nested boxes, T(d) = Σ F_layer over the layers entered,
///   while ‖v‖ > ε. §6.2 renders T as the slip threshold of a proxy of stiffness
///   k_c that is preloaded at each pop (the step of R4) and sticks when a box is
///   entered later, the force climbing at k_c per mm of travel until it reaches
///   the new sum: for forward motion F(d) = min over the travel s since the last
///   pop P of [T(s) + k_c·(d − s)], with T(P) the preloaded sum;
/// - friction (Eq. 1's third term, §2.1): v·Σ b·l over the shaft in the layers
///   entered, and a tenting layer's pushed span (the tip is inside its dimple).
ClosedFormCheck senacProfile(const Case& c, const Lookup& in, const std::vector<Sample>& samples)
{
    SenacRun run;
    if (std::string why = senacPreconditions(c, in, run); !why.empty()) return ClosedFormCheck::none(why);
    double thickness[kMidlineLayers];
    if (std::string why = midlineThicknesses(in, thickness); !why.empty()) return ClosedFormCheck::none(why);
    std::vector<SenacLayer> layers;
    if (std::string why = senacLayers(in, thickness, run.h, layers); !why.empty()) return ClosedFormCheck::none(why);
    const SenacModel m(run, std::move(layers));

    ClosedForm cf;
    cf.id = "R4";
    cf.rule = "physics.md §7 R4 (Sénac nested boxes, §6.2 proxy)";
    cf.modelN.assign(samples.size(), 0.0);
    cf.toleranceN.assign(samples.size(), 0.0);
    // Each segment between pops takes the reading of its ties nearer the run.
    std::vector<bool> reading(m.ties.size(), true);
    for (std::size_t seg = 0; seg <= m.pops.size(); ++seg) {
        const double lo = seg == 0 ? -std::numeric_limits<double>::infinity() : m.pops[seg - 1];
        const double hi = seg < m.pops.size() ? m.pops[seg] : std::numeric_limits<double>::infinity();
        const std::vector<std::vector<bool>> options = segmentReadings(m, seg, reading);
        reading = options[nearestReading(m, options, samples, lo, hi)];
        for (std::size_t i = 0; i < samples.size(); ++i) {
            const double d = samples[i].depthMm;
            if (d < lo || d >= hi) continue;
            const SenacEval e = m.evaluate(d, reading);
            cf.modelN[i] = e.f;
            cf.toleranceN[i] = m.tolerance(d, e);
        }
    }
    expectPops(cf, m, samples.empty() ? 0.0 : samples.back().depthMm);
    return cf;
}

} // namespace

std::string ClosedFormCheck::line() const { return form ? "closed form: " + form->id : "no closed form: " + why; }

ClosedFormCheck closedForm(
    const Case& c, const Inputs& recorded, const Inputs& current, const std::vector<Sample>& samples)
{
    const Lookup in{recorded, current};
    if (c.sweep) return ClosedFormCheck::none("a palpation sweep (§7 has no profile across the back)");
    // The closed forms are those of a straight needle; a bending one's tip lags them by
    // what its deflection takes from the depth (physics.md §9.1).
    if (termOn(in, "bending")) return ClosedFormCheck::none("a bending needle (§7's forms are a straight needle's)");
    const std::string model = in.text("scene.model"), layersFrom = in.text("scene.layers");
    if (model == "lumbar-puncture" && layersFrom == "table") return lumbarPunctureStack(c, in, samples);
    if (model == "conci" && layersFrom == "table") return conciProfile(c, in, samples);
    if (model == "senac") return senacProfile(c, in, samples);
    if (model == "lumbar-puncture" || model == "conci")
        return ClosedFormCheck::none("the " + model + " model on labels (R2 and R3 hold for its fixed table)");
    const std::string kind = c.volume.kind.empty() ? in.text("phantom.kind") : c.volume.kind;
    if (kind != "slab" && kind != "sphere")
        return ClosedFormCheck::none("the " + kind + " phantom (R1 and R5 hold on the slab and the sphere)");
    if (!c.script.empty()) return ClosedFormCheck::none(kScripted);
    if (const std::string why = notDampingOnly(in.current); !why.empty()) return ClosedFormCheck::none(why);
    const auto entry = vecOf(in.current.at("case.entry").text), target = vecOf(in.current.at("case.target").text);
    const auto speed = in.current.find("case.speed_mm_per_s");
    if (!entry || !target || speed == in.current.end() || !speed->second.number) return ClosedFormCheck::none(kNoSpeed);
    const Vec3d u = (*target - *entry).normalized();
    const double v0 = *speed->second.number;
    const double needle = in.number("scene.needle.length_mm").value_or(90.0); // §3.3: the default needle, 90 mm
    // β of each tissue on the path, from the record (regress's own law: recordedBeta).
    std::map<std::string, double> betas;
    std::string missing;
    const auto beta = [&](const std::string& tissue) {
        auto it = betas.find(tissue);
        if (it != betas.end()) return it->second;
        const std::optional<double> b = recordedBeta(in, tissue);
        if (!b && missing.empty()) missing = tissue;
        return betas[tissue] = b.value_or(0.0);
    };
    // §6.2's split, with the scene's cap and reference speed and the device's
    // maximum damping as the run recorded them (else §1.1's 6 N, [K01]'s 10 mm/s
    // and the touch preset's 0.002 N·s/mm of §6.3).
    const double capN = in.number("damping.cap_N").value_or(6.0);
    const double referenceSpeed = in.number("damping.reference_speed_mm_per_s").value_or(10.0);
    const double bDevice = in.number("device.max_damping_Ns_per_mm").value_or(0.002);
    // The split is Lipschitz in ∫β with constant max(v, v_ref) (§6.2): the bound on ∫β times it bounds F.
    const double lipschitz = std::max(v0, referenceSpeed);

    const double h = c.volume.spacingMm.maxCoeff();
    const double step = 0.25 * c.volume.spacingMm.minCoeff(); // the march step (CaseRunner.cpp)
    const std::string& strategy = c.strategy;

    ClosedForm cf;
    std::function<double(double, double)> integral; // ∫β over the shaft [a, s] of the path
    double boundTerm = 0;                           // bound on |Δ∫β| [N·s/mm]

    if (kind == "slab") {
        std::vector<std::pair<std::string, double>> layers = c.volume.layers;
        if (layers.empty()) {
            for (const auto& l : volume::SlabParams{}.layers) layers.emplace_back(l.tissue, l.thicknessMm);
        }
        for (const auto& [t, mm] : layers) {
            if (const std::string why = notDampingTissue(in, t); !why.empty()) return ClosedFormCheck::none(why);
        }
        const double tilt = c.volume.tiltDeg * kPi / 180.0;
        const Vec3d normal(0.0, std::cos(tilt), std::sin(tilt)); // SlabPhantoms.cpp: outward normal
        const double cosT = -u.dot(normal);
        if (!(cosT > 0.2)) return ClosedFormCheck::none("a path within 11.5° of the layers' plane");
        const double d0 = -normal.dot(*entry); // the entry's depth below the surface
        std::vector<double> z{0.0}, b;
        for (const auto& [t, mm] : layers) z.push_back(z.back() + mm), b.push_back(beta(t));
        integral = [=](double a, double s) {
            double sum = 0;
            for (std::size_t j = 0; j < b.size(); ++j)
                sum += b[j] * overlap(d0 + a * cosT, d0 + s * cosT, z[j], z[j + 1]);
            return sum / cosT;
        };
        // Boundaries fall on voxel faces when the grid is turned with the layers
        // (rotation (tilt, 0, 0)), the entry lies on the surface and the spacing
        // across the layers divides every depth (physics.md §7 R1); otherwise each
        // voxelised plane lies within half a voxel diagonal of the true one
        // (TestPhantoms: TiltedLayersWithinHalfAVoxelDiagonal), a band √3·h/cosθ
        // long on the path.
        const double hy = c.volume.spacingMm.y();
        bool aligned = (c.volume.rotationDeg - Vec3d(c.volume.tiltDeg, 0, 0)).norm() < 1e-12 && std::abs(d0) < 1e-9;
        for (const double depth : z) aligned = aligned && std::abs(depth / hy - std::round(depth / hy)) < 1e-9;
        double sumJump = 0, maxJump = 0;
        for (std::size_t j = 0; j <= b.size(); ++j) {
            const double jump = std::abs((j < b.size() ? b[j] : 0.0) - (j > 0 ? b[j - 1] : 0.0));
            sumJump += jump;
            maxJump = std::max(maxJump, jump);
        }
        if (!aligned) boundTerm += sumJump * std::sqrt(3.0) * h / cosT;
        if (strategy == "march-trilinear")
            boundTerm += maxJump * h / (8 * cosT) + sumJump * cosT * step * step / (4 * h); // R1's bound
        else if (strategy == "exact-trilinear")
            boundTerm += maxJump * h / (8 * cosT); // R1's smearing term
        else if (strategy == "march-nearest")
            boundTerm += sumJump * step; // the trapezoid rule across each jump
        cf.id = "R1";
        cf.rule = "physics.md §7 R1 (layered damping slab" + std::string(c.volume.tiltDeg != 0 ? ", tilted" : "") + ")";
    } else {
        const double T = c.volume.slabThicknessMm, R = c.volume.radiusMm;
        const Vec3d centre(0.0, -0.5 * T, 0.0); // SlabPhantoms.cpp: sphereModel
        for (const std::string& t : {c.volume.slabTissue, c.volume.sphereTissue}) {
            if (const std::string why = notDampingTissue(in, t); !why.empty()) return ClosedFormCheck::none(why);
        }
        const double b0 = beta(c.volume.slabTissue), bs = beta(c.volume.sphereTissue);
        if (!(std::abs(u.y()) > 0.2)) return ClosedFormCheck::none("a path within 11.5° of the slab's plane");
        // The slab's planes y = 0 and y = -T along the path, and the sphere's chord.
        const double y0 = entry->y();
        const double sIn = (y0 - 0.0) / -u.y(), sOut = (y0 + T) / -u.y();
        const double m = (centre - *entry).dot(u);
        const double rho2 = (centre - *entry).squaredNorm() - m * m;
        if (rho2 > 0.64 * R * R) // R5's voxel bound holds for ρ ≤ 0.8R
            return ClosedFormCheck::none("a path more than 0.8 R from the sphere's centre (R5's voxel bound)");
        const double half = std::sqrt(R * R - rho2);
        integral = [=](double a, double s) {
            return b0 * overlap(a, s, std::min(sIn, sOut), std::max(sIn, sOut)) +
                (bs - b0) * overlap(a, s, m - half, m + half);
        };
        const double jump = std::abs(bs - b0);
        boundTerm += 2 * h * jump; // R5: |ΔF| ≤ 2h·|Δβ|·v0
        const bool gridTurned = c.volume.rotationDeg.norm() > 1e-12;
        if (gridTurned) boundTerm += 2 * b0 * std::sqrt(3.0) * h / std::abs(u.y());
        if (strategy == "march-trilinear")
            boundTerm += std::max(jump, b0) * h / 8 + (2 * jump + 2 * b0) * step * step / (4 * h);
        else if (strategy == "exact-trilinear")
            boundTerm += std::max(jump, b0) * h / 8;
        else if (strategy == "march-nearest")
            boundTerm += (2 * jump + 2 * b0) * step;
        cf.id = "R5";
        cf.rule = "physics.md §7 R5 (sphere in a slab)";
    }
    if (!missing.empty()) return ClosedFormCheck::none(missing + " has no damping or T1 in the record");
    // R1 and R5 take the layers as unbounded; the phantoms are blocks ±w wide in
    // x and z (§7), cut on the voxels within a voxel diagonal of that. A tilted
    // or oblique path may leave the block sideways: from there the tip (the
    // shaft's farthest point from the entry) is not compared.
    const double halfWidth = kind == "slab" ? volume::SlabParams{}.halfWidthMm : volume::SphereParams{}.halfWidthMm;
    const double inside = halfWidth - std::sqrt(3.0) * h;
    for (const Sample& smp : samples) {
        const double s = smp.depthMm;
        const double f = dampingForceN(integral(s - needle, s), v0, bDevice, capN, referenceSpeed);
        cf.modelN.push_back(f);
        const Vec3d tip = *entry + s * u;
        if (std::abs(tip.x()) > inside || std::abs(tip.z()) > inside) {
            cf.toleranceN.push_back(std::numeric_limits<double>::infinity());
            continue;
        }
        // R1: exact traversal to 1e-9 relative, and the material field's float β
        // (kFloatBeta); the rest as bounded above.
        cf.toleranceN.push_back(lipschitz * boundTerm + (1e-9 + kFloatBeta) * std::abs(f) + 1e-9);
    }
    return cf;
}

} // namespace voxhap::regress
