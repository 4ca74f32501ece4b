// SPDX-License-Identifier: Apache-2.0
/// @file CaseRunner.cpp
/// @brief Setting up and running regression cases, their fingerprints and the
/// closed forms of physics.md §7.

#include "regress/CaseRunner.h"

#include "core/BoundedRead.h"
#include "core/Errors.h"
#include "core/Version.h"
#include "haptic/beam/Foundation.h"
#include "haptic/scene/Scene.h"
#include "haptic/scene/ScriptedInsertion.h"
#include "haptic/shaft/LabelTrace.h"
#include "phantoms/Phantoms.h"
#include "registration/Resample.h"
#include "volume/TissueTable.h"

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <set>

namespace voxhap::haptic {
// The scene files compiled in (SceneBuiltin.cpp, generated from data/scenes/):
// their text is part of a case's fingerprint.
const std::vector<std::pair<std::string, std::string>>& builtinSceneFiles();
} // namespace voxhap::haptic

namespace voxhap::regress {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using Clock = std::chrono::steady_clock;

/// Shortest text that reads back as the same double (nlohmann's round trip).
std::string numberText(double v) { return Json(v).dump(); }

void putNumber(Inputs& in, const std::string& key, double v, const std::string& unit)
{
    in[key] = InputValue{numberText(v), v, unit};
}
void putText(Inputs& in, const std::string& key, const std::string& text) { in[key] = InputValue{text, {}, ""}; }
std::string vecText(const Vec3d& v)
{
    return "[" + numberText(v.x()) + ", " + numberText(v.y()) + ", " + numberText(v.z()) + "]";
}

/// A scene file flattened into "scene.terms.damping.cap_N" keys; its prose
/// (name, description, sources) shapes nothing and is left out. An object
/// without parameters is recorded as "{}": `"lock": {}` turns a term on.
void flattenScene(const Json& j, const std::string& prefix, Inputs& out)
{
    for (const auto& [k, v] : j.items()) {
        // "assessment" holds the trainee metrics' reference ranges (`voxhap assess`), which no force depends on.
        if (k == "description" || k == "source" || k == "name" || k == "schema" || k == "assessment") continue;
        const std::string key = prefix + "." + k;
        bool bare = v.is_object(); // no parameters, only prose
        for (const auto& [k2, v2] : v.items()) bare = bare && (k2 == "description" || k2 == "source" || k2 == "name");
        if (bare) {
            putText(out, key, "{}");
        } else if (v.is_object()) {
            flattenScene(v, key, out);
        } else if (v.is_number()) {
            putNumber(out, key, v.get<double>(), "");
        } else {
            putText(out, key, v.is_string() ? v.get<std::string>() : v.dump());
        }
    }
}

/// Rotation from Euler angles [deg] about x, then y, then z.
Mat3d rotationFromDegrees(const Vec3d& deg)
{
    const auto axis = [](double d, const Vec3d& a) { return Eigen::AngleAxisd(d * kPi / 180.0, a); };
    return (axis(deg.z(), Vec3d::UnitZ()) * axis(deg.y(), Vec3d::UnitY()) * axis(deg.x(), Vec3d::UnitX()))
        .toRotationMatrix();
}

/// The phantom spec of a scene's own volume, in the suite's terms.
VolumeSpec specOfScene(const haptic::VolumeSource& s)
{
    VolumeSpec v;
    v.kind = s.file.empty() ? s.phantom : "file";
    v.file = s.file;
    v.spacingMm = Vec3d::Constant(s.spacingMm);
    v.preset = s.preset;
    v.bmi = s.bmi;
    return v;
}

std::string hexDigest(std::uint64_t h)
{
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", (unsigned long long)h);
    return hex;
}

/// FNV-1a of a file's bytes, read in chunks (a volume may be large); a folder
/// (DICOM) by the names and sizes of its files.
std::string fileDigest(const fs::path& path)
{
    std::uint64_t h = fnv1a(nullptr, 0);
    if (fs::is_directory(path)) {
        std::vector<std::pair<std::string, std::uintmax_t>> files;
        for (const auto& e : fs::recursive_directory_iterator(path)) {
            if (e.is_regular_file()) files.emplace_back(e.path().string(), e.file_size());
        }
        std::sort(files.begin(), files.end());
        for (const auto& [name, size] : files) {
            h = fnv1a(name.data(), name.size(), h);
            h = fnv1a(&size, sizeof size, h);
        }
    } else {
        std::ifstream in(path, std::ios::binary);
        std::vector<char> buf(1 << 16);
        while (in.read(buf.data(), std::streamsize(buf.size())) || in.gcount() > 0)
            h = fnv1a(buf.data(), std::size_t(in.gcount()), h);
    }
    return hexDigest(h);
}

/// Every field of the spec that shapes the volume, as fingerprint inputs.
void recordVolume(const VolumeSpec& v, Inputs& in)
{
    putText(in, "phantom.kind", v.kind);
    if (v.kind == "file") {
        putText(in, "volume.file", v.file);
        putText(in, "volume.fnv1a", fileDigest(v.file));
        return;
    }
    putText(in, "phantom.spacing_mm", vecText(v.spacingMm));
    putText(in, "phantom.rotation_deg", vecText(v.rotationDeg));
    if (v.kind == "slab") {
        putNumber(in, "phantom.tilt_deg", v.tiltDeg, "deg");
        std::string layers;
        for (const auto& [t, mm] : v.layers) layers += (layers.empty() ? "" : ", ") + t + " " + numberText(mm) + " mm";
        putText(in, "phantom.layers", layers.empty() ? "default" : layers);
        if (v.fusedMr) {
            putNumber(in, "phantom.fused_mr.turn_deg", v.fusedMr->turnDeg, "deg");
            putText(in, "phantom.fused_mr.shift_mm", vecText(v.fusedMr->shiftMm));
            if (v.fusedMr->mapErrorMm != Vec3d::Zero())
                putText(in, "phantom.fused_mr.map_error_mm", vecText(v.fusedMr->mapErrorMm));
        }
    } else if (v.kind == "sphere") {
        putText(in, "phantom.slab_tissue", v.slabTissue);
        putText(in, "phantom.sphere_tissue", v.sphereTissue);
        putNumber(in, "phantom.radius_mm", v.radiusMm, "mm");
        putNumber(in, "phantom.slab_thickness_mm", v.slabThicknessMm, "mm");
    } else if (v.kind == "lumbar") {
        putText(in, "phantom.preset", v.preset);
        putText(in, "phantom.bmi", v.bmi ? numberText(*v.bmi) : "none");
    } else if (v.kind == "torso") {
        putNumber(in, "phantom.lesion_radius_mm", v.lesionRadiusMm, "mm");
    }
}

std::string volumeKey(const VolumeSpec& v, const std::string& tableKey)
{
    Inputs in;
    recordVolume(v.kind == "file" ? VolumeSpec{} : v, in);
    std::string key = tableKey + "|" + v.kind + "|" + v.file;
    for (const auto& [k, val] : in) key += "|" + k + "=" + val.text;
    return key;
}

/// A tissue row's parameters in canonical units (TissueTable.h), as inputs "skin.cutting_force".
void recordTissue(const volume::Tissue& t, Inputs& in)
{
    const std::string p = t.name + ".";
    putNumber(in, p + "id", t.id, "");
    putText(in, p + "critical", t.critical ? "true" : "false");
    putText(in, p + "rigid", t.rigid ? "true" : "false");
    putNumber(in, p + "hu_typical", t.huTypical, "HU");
    putNumber(in, p + "t1_1.5T", t.t1At1p5T.value, "ms");
    putNumber(in, p + "t1_3T", t.t1At3T.value, "ms");
    const auto opt = [&](const char* key, const std::optional<volume::Quantity>& q, const char* unit) {
        if (q) putNumber(in, p + key, q->value, unit);
    };
    opt("thickness", t.thickness, "mm");
    opt("puncture_force", t.punctureForce, "N");
    opt("cutting_force", t.cuttingForce, "N");
    opt("elasticity", t.elasticity, "N/mm");
    opt("friction_viscous", t.frictionViscous, "N·s/mm²");
    opt("friction_coulomb", t.frictionCoulomb, "N");
    opt("damping", t.damping, "N·s/mm²");
}

haptic::Strategy strategyOf(const std::string& name)
{
    if (name == "exact-trilinear") return haptic::Strategy::ExactTrilinear;
    if (name == "march-trilinear") return haptic::Strategy::MarchTrilinear;
    if (name == "march-nearest") return haptic::Strategy::MarchNearest;
    return haptic::Strategy::ExactVoxel;
}

/// The march step of a case: a quarter voxel, as physics.md §7 R1 advises (Δs ≤ h/4).
double marchStepMm(const Vec3d& spacing) { return 0.25 * spacing.minCoeff(); }

/// The force model of a case. "servo" is exactly what the scene runs in the servo
/// loop; the other strategies integrate the shaft one way throughout.
std::unique_ptr<haptic::NeedleForceModel> makeModel(const haptic::SceneInstance& inst, const std::string& strategy)
{
    if (strategy == "servo" || !inst.field()) return inst.makeModel();
    const haptic::Scene& s = inst.scene();
    haptic::IntegratorOptions o;
    o.strategy = strategyOf(strategy);
    o.stepMm = marchStepMm(inst.volume().geometry().spacing);
    o.trackLabels = s.terms.critical && inst.field()->labels();
    std::unique_ptr<haptic::ShaftIntegrator> integrator;
    if (s.terms.damping.on || o.trackLabels) integrator = haptic::makeIntegrator(*inst.field(), o);
    return std::make_unique<haptic::NeedleForceModel>(haptic::ForceModelSetup{.layers = inst.layers(),
        .path = haptic::NeedlePath{inst.entry(), inst.target() - inst.entry()},
        .terms = s.terms,
        .needle = s.needle,
        .device = s.device,
        .integrator = std::move(integrator),
        .field = inst.field(),
        // A bending needle's tissue (physics.md §9.2), as the scene builds it.
        .foundation = s.terms.bending.on ? haptic::makeLabelFoundation(*inst.field()) : nullptr});
}

/// A palpation sweep (Suite.h) through @p model at @p rateHz: down onto the skin,
/// across it pressed in, and up, the needle held along @p direction. Each row's
/// depth is the distance travelled so far, its axial force the model's push out
/// of the skin (along −direction), so that the profile reads against travel.
haptic::InsertionResult runSweep(
    haptic::NeedleForceModel& model, const PalpationSweep& s, const Vec3d& direction, double rateHz)
{
    const Vec3d corners[4] = {s.from - s.aboveMm * direction, s.from + s.pressMm * direction,
        s.to + s.pressMm * direction, s.to - s.aboveMm * direction};
    double length[3], total = 0;
    for (int i = 0; i < 3; ++i) total += length[i] = (corners[i + 1] - corners[i]).norm();
    const double dt = 1.0 / rateHz, stepMm = s.speedMmPerS * dt;
    const long ticks = long(std::ceil(total / stepMm - 1e-9)) + 1;
    haptic::InsertionResult r;
    r.rows.reserve(std::size_t(ticks));
    haptic::NeedleOutput out;
    for (long n = 0; n < ticks; ++n) {
        const double travelled = std::min(double(n) * stepMm, total);
        int seg = 0;
        double along = travelled;
        while (seg < 2 && along > length[seg]) along -= length[seg++];
        const Vec3d unit = (corners[seg + 1] - corners[seg]) / length[seg];
        haptic::NeedleInput in;
        in.timeS = double(n) * dt;
        in.dtS = dt;
        in.tip = corners[seg] + std::min(along, length[seg]) * unit;
        in.direction = direction;
        in.velocity = travelled < total ? Vec3d(s.speedMmPerS * unit) : Vec3d::Zero();
        model.step(in, out);
        haptic::InsertionRow row;
        row.timeS = in.timeS;
        row.depthMm = travelled;
        row.force = out.force;
        row.axialN = -out.modelForce.dot(direction);
        row.firstEvent = int(r.events.size());
        row.eventCount = out.events.size();
        for (const haptic::Event& e : out.events) r.events.push_back(e);
        r.summary.peakModelN = std::max(r.summary.peakModelN, out.modelForce.norm());
        r.summary.peakRenderedN = std::max(r.summary.peakRenderedN, out.force.norm());
        r.rows.push_back(row);
    }
    r.summary.finalDepthMm = total;
    r.summary.durationS = double(ticks - 1) * dt;
    return r;
}

/// The stored profile: a sample every @p stepMm of travel, and the last tick; the
/// digest covers every tick, so that "bit for bit" is checked on all of them.
Profile profileOf(const haptic::InsertionResult& r, double stepMm)
{
    Profile p;
    std::uint64_t h = fnv1a(nullptr, 0);
    double travelled = 0, sinceLast = stepMm; // the first tick is kept
    const double inf = std::numeric_limits<double>::infinity();
    const Envelope empty{inf, -inf, inf, -inf, inf, -inf};
    Envelope e = empty;
    for (std::size_t i = 0; i < r.rows.size(); ++i) {
        const haptic::InsertionRow& row = r.rows[i];
        const double bits[6] = {row.depthMm, row.axialN, row.force.x(), row.force.y(), row.force.z(), row.plungerN};
        h = fnv1a(bits, sizeof bits, h);
        const double rendered = row.force.norm();
        e = {std::min(e.modelMin, row.axialN), std::max(e.modelMax, row.axialN), std::min(e.renderedMin, rendered),
            std::max(e.renderedMax, rendered), std::min(e.plungerMin, row.plungerN),
            std::max(e.plungerMax, row.plungerN)};
        if (i > 0) {
            const double step = std::abs(row.depthMm - r.rows[i - 1].depthMm);
            travelled += step;
            sinceLast += step;
        }
        if (sinceLast >= stepMm * (1 - 1e-9) || i + 1 == r.rows.size()) {
            p.samples.push_back({row.depthMm, row.axialN, rendered, row.plungerN});
            p.envelope.push_back(e);
            e = empty;
            sinceLast = 0;
        }
    }
    for (const haptic::Event& ev : r.events) p.events.push_back({haptic::eventName(ev.type), ev.depthMm});
    p.peakModelN = r.summary.peakModelN;
    p.peakRenderedN = r.summary.peakRenderedN;
    p.digest = hexDigest(h);
    return p;
}

} // namespace

std::uint64_t fnv1a(const void* data, std::size_t bytes, std::uint64_t hash)
{
    const auto* b = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < bytes; ++i) hash = (hash ^ b[i]) * 1099511628211ull;
    return hash;
}

/// What one case needs, resolved before anything runs.
struct Prepared {
    const volume::TissueTable* table = nullptr;
    haptic::Scene scene;
    Json sceneJson;
    VolumeSpec volume;
    std::string volumeKey;
};

struct Built {
    std::shared_ptr<const volume::Volume> volume;
    std::optional<volume::PhantomModel> model;
};

struct Runner::Impl {
    std::map<std::string, std::unique_ptr<volume::TissueTable>> tables;
    std::vector<Prepared> cases;
    std::map<std::string, Built> models;  ///< by phantom spec: the analytic models
    std::map<std::string, Built> volumes; ///< by spec and crop box: the rasterised volumes
    std::vector<std::string> keys;        ///< each selected case's volume
};

namespace {

[[noreturn]] void caseFail(const Suite& s, const Case& c, const std::string& field, const std::string& why)
{
    throw ValueError(s.origin + ": cases." + c.name + "." + field + ": " + why);
}

/// The file a case's scene comes from: DIR/NAME.json from --scenes when it
/// exists, else the built-in NAME or the file the case names.
std::string sceneRef(const Case& c, const fs::path& scenesDir)
{
    if (!scenesDir.empty() && c.scene.find('/') == std::string::npos) {
        const fs::path edited = scenesDir / (c.scene + ".json");
        if (fs::exists(edited)) return edited.string();
    }
    return c.scene;
}

/// A scene NAME, DIR/NAME.json from --scenes when it exists, or a file.
std::pair<haptic::Scene, Json> resolveScene(const Suite& s, const Case& c, const fs::path& scenesDir)
{
    const std::string ref = sceneRef(c, scenesDir);
    try {
        for (const auto& [name, text] : haptic::builtinSceneFiles()) {
            if (name == ref) return {haptic::parseScene(text, "builtin:" + name), Json::parse(text)};
        }
        haptic::Scene scene = haptic::loadScene(ref);
        return {scene, Json::parse(readBoundedFile(ref, "scene file"))};
    } catch (const Error& e) {
        caseFail(s, c, "scene", e.what());
    }
}

/// The phantom's analytic model (cheap: nothing rasterised yet); a file has none.
Built phantomModel(const VolumeSpec& v, const volume::TissueTable& table)
{
    Built b;
    if (v.kind == "file") return b;
    volume::PhantomSpec spec;
    spec.kind = v.kind;
    spec.slab.tiltDeg = v.tiltDeg;
    if (!v.layers.empty()) {
        spec.slab.layers.clear();
        for (const auto& [t, mm] : v.layers) spec.slab.layers.push_back({t, mm});
    }
    spec.sphere.slabTissue = v.slabTissue;
    spec.sphere.sphereTissue = v.sphereTissue;
    spec.sphere.radiusMm = v.radiusMm;
    spec.sphere.slabThicknessMm = v.slabThicknessMm;
    spec.lumbar.preset = volume::parseLumbarPreset(v.preset);
    spec.lumbar.bmi = v.bmi;
    spec.torso.lesionRadiusMm = v.lesionRadiusMm;
    b.model = volume::phantomModel(spec, table);
    return b;
}

/// Rasterise the model within @p crop (a box around the paths of the cases
/// that share it, or nothing: the whole phantom), or load the file.
void buildVolume(
    Built& b, const VolumeSpec& v, const volume::TissueTable& table, const std::optional<volume::WorldBox>& crop)
{
    if (!b.model) {
        haptic::VolumeSource src;
        src.file = v.file;
        b.volume = haptic::makeSourceVolume(src, table);
        return;
    }
    volume::GridSpec grid;
    grid.spacing = v.spacingMm;
    grid.direction = rotationFromDegrees(v.rotationDeg);
    volume::PhantomModel model = *b.model;
    if (crop) {
        model.bounds.min = model.bounds.min.cwiseMax(crop->min);
        model.bounds.max = model.bounds.max.cwiseMin(crop->max);
    }
    volume::Volume ct = volume::makePhantom(model, grid, table);
    if (v.fusedMr) {
        // The MR: the same phantom on a grid turned about the layers' normal,
        // its frame then moved by the shift, so that the CT point x is the MR
        // point x + shift; fused through that map as `voxhap fuse` resamples.
        volume::GridSpec mrGrid = grid;
        mrGrid.direction =
            Eigen::AngleAxisd(v.fusedMr->turnDeg * 3.14159265358979323846 / 180.0, Vec3d::UnitY()).toRotationMatrix();
        const volume::Volume scanned = volume::makePhantom(model, mrGrid, table);
        volume::Geometry g = scanned.geometry();
        g.origin += v.fusedMr->shiftMm;
        volume::Volume mr(g, scanned.indexBox());
        mr.setGrid(volume::Channel::T1,
            std::const_pointer_cast<openvdb::GridBase>(scanned.grid(volume::Channel::T1))->deepCopyGrid());
        const registration::AffineMap map{Mat3d::Identity(), v.fusedMr->shiftMm + v.fusedMr->mapErrorMm};
        ct.setGrid(volume::Channel::T1, registration::resampleOnto(ct, mr, volume::Channel::T1, map));
    }
    b.volume = std::make_shared<const volume::Volume>(std::move(ct));
}

/// The path of a case: its points, else landmarks (the case's, else the
/// scene's), else the phantom's reference path (the slab and the sphere have
/// no scene landmarks). Landmarks come from the model, or a file's metadata.
std::pair<std::optional<Vec3d>, std::optional<Vec3d>> casePath(
    const Suite& suite, const Case& c, const haptic::Scene& scene, const Built& b)
{
    const auto pick = [&](const std::optional<Vec3d>& given, const std::string& caseMark, const std::string& sceneMark,
                          bool isEntry) -> std::optional<Vec3d> {
        if (given) return given;
        const std::string mark = caseMark.empty() ? sceneMark : caseMark;
        if (!mark.empty()) {
            if (b.model) {
                for (const auto& [name, point] : b.model->landmarks) {
                    if (name == mark) return point;
                }
            } else if (auto lm = volume::phantomLandmark(*b.volume, mark)) {
                return lm;
            }
            if (!caseMark.empty())
                caseFail(suite, c, isEntry ? "insertion.entry_landmark" : "insertion.target_landmark",
                    "the volume has no landmark '" + mark + "'");
        }
        if (b.model) return isEntry ? b.model->pathEntry : b.model->pathTarget;
        return std::nullopt;
    };
    return {pick(c.entry, c.entryLandmark, scene.entryLandmark, true),
        pick(c.target, c.targetLandmark, scene.targetLandmark, false)};
}

/// The world box a constant-speed case reads: the needle's line from where the
/// tip starts to where the scene traces its layers (entry + path length + needle
/// length, SceneInstance), widened by a margin for the trilinear strategies'
/// neighbours. Voxels outside it never meet the shaft, and the lattice is
/// anchored at the world origin, so each voxel inside keeps its value.
volume::WorldBox pathBox(
    const Vec3d& entry, const Vec3d& target, const haptic::Scene& scene, const Case& c, const VolumeSpec& v)
{
    const Vec3d u = (target - entry).normalized();
    const double length = (target - entry).norm();
    const double depth = c.depthMm.value_or(scene.depthMm.value_or(length));
    const double reach = std::max(depth, length) + scene.needle.lengthMm;
    const Vec3d a = entry - (scene.approachMm + scene.needle.lengthMm) * u, b = entry + reach * u;
    const double margin = 5.0 + 3.0 * v.spacingMm.maxCoeff(); // [mm]
    return {a.cwiseMin(b) - Vec3d::Constant(margin), a.cwiseMax(b) + Vec3d::Constant(margin)};
}

} // namespace

Runner::Runner(const Suite& suite, std::vector<std::size_t> selected, const RunOptions& options)
    : mSuite(suite), mSelected(std::move(selected)), mOptions(options), mImpl(std::make_unique<Impl>())
{
    for (const std::size_t i : mSelected) {
        const Case& c = suite.cases.at(i);
        Prepared p;
        const std::string tableFile = !options.tissues.empty() ? options.tissues : c.tissues;
        auto& slot = mImpl->tables[tableFile];
        if (!tableFile.empty() && !slot) {
            try {
                slot = std::make_unique<volume::TissueTable>(volume::TissueTable::load(tableFile));
            } catch (const Error& e) {
                if (!options.tissues.empty()) throw ValueError("--tissues: " + std::string(e.what()));
                caseFail(suite, c, "tissues", e.what());
            }
        }
        p.table = tableFile.empty() ? &volume::TissueTable::builtin() : slot.get();
        std::tie(p.scene, p.sceneJson) = resolveScene(suite, c, options.scenesDir);
        // A scene naming a tissue the table does not have would change nothing,
        // silently: a misspelt override would look like an edit that moves no force.
        const std::string sceneFile = sceneRef(c, options.scenesDir);
        for (const auto& [name, unused] : p.scene.recipe.overrides) {
            if (!p.table->find(name))
                caseFail(suite, c, "scene",
                    sceneFile + ": overrides." + name + ": unknown tissue '" + name + "' (not in " + p.table->origin() +
                        ")");
        }
        if (p.scene.recipe.model == haptic::LayerModel::Senac) { // the only model that tents by name
            for (const std::string& name : p.scene.recipe.tenting) {
                if (!p.table->find(name))
                    caseFail(suite, c, "scene",
                        sceneFile + ": tenting: unknown tissue '" + name + "' (not in " + p.table->origin() + ")");
            }
        }
        if (!p.scene.terms.damping.on && c.strategy != "servo" && c.strategy != "exact-voxel")
            caseFail(suite, c, "strategy",
                "scene '" + p.scene.name +
                    "' integrates no voxel damping: its shaft only tracks labels (servo or exact-voxel)");
        p.volume = c.volume.kind.empty() ? specOfScene(p.scene.volume) : c.volume;
        if (p.volume.kind == "slab") {
            for (const auto& [t, mm] : p.volume.layers) {
                if (!p.table->find(t)) caseFail(suite, c, "volume.layers", "unknown tissue '" + t + "'");
            }
        } else if (p.volume.kind == "sphere") {
            if (!p.table->find(p.volume.slabTissue))
                caseFail(suite, c, "volume.slab_tissue", "unknown tissue '" + p.volume.slabTissue + "'");
            if (!p.table->find(p.volume.sphereTissue))
                caseFail(suite, c, "volume.sphere_tissue", "unknown tissue '" + p.volume.sphereTissue + "'");
        }
        if (c.sweep && !p.scene.terms.palpation.on)
            caseFail(suite, c, "palpation_sweep", "scene '" + p.scene.name + "' does not turn palpation on");
        if (!c.script.empty()) {
            try {
                (void)haptic::InsertionScript::load(c.script);
            } catch (const Error& e) {
                caseFail(suite, c, "insertion.script", e.what());
            }
        }
        p.volumeKey = volumeKey(p.volume, tableFile);
        mImpl->cases.push_back(std::move(p));
    }
}

Runner::~Runner() = default;

std::size_t Runner::volumeCount() const { return mImpl->volumes.size(); }

std::vector<CaseRun> Runner::run()
{
    tbb::task_arena arena(mOptions.threads > 0 ? mOptions.threads : tbb::task_arena::automatic);
    std::vector<CaseRun> runs(mSelected.size());
    arena.execute([&] {
        // Each distinct volume once, in a fixed order; the rasteriser itself is
        // parallel and writes each voxel from one task only. A phantom is
        // rasterised only around the case's own path: the shaft reads nothing
        // else, and most of a torso is far from its needle. The box is the
        // case's alone (cases share a volume only when their boxes agree), so
        // that --only, which changes which cases run, changes no result.
        const auto t0 = Clock::now();
        mImpl->keys.assign(mSelected.size(), std::string());
        for (std::size_t k = 0; k < mSelected.size(); ++k) {
            const Prepared& p = mImpl->cases[k];
            const Case& c = mSuite.cases[mSelected[k]];
            try {
                if (!mImpl->models.count(p.volumeKey)) mImpl->models[p.volumeKey] = phantomModel(p.volume, *p.table);
            } catch (const Error& e) {
                caseFail(mSuite, c, "volume", e.what());
            }
            const Built& model = mImpl->models[p.volumeKey];
            std::optional<volume::WorldBox> crop;
            if (model.model && c.script.empty() && !c.sweep) { // a script or a sweep may go anywhere: the whole phantom
                const auto [entry, target] = casePath(mSuite, c, p.scene, model);
                if (entry && target && (*target - *entry).norm() > 1e-6)
                    crop = pathBox(*entry, *target, p.scene, c, p.volume);
            }
            std::string key = p.volumeKey;
            if (crop) key += "|crop " + vecText(crop->min) + " " + vecText(crop->max);
            mImpl->keys[k] = key;
            if (mImpl->volumes.count(key)) continue;
            Built b = model;
            try {
                buildVolume(b, p.volume, *p.table, crop);
            } catch (const Error& e) {
                caseFail(mSuite, c, "volume", e.what());
            }
            mImpl->volumes[key] = std::move(b);
        }
        mVolumeSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
        // Cases in parallel: each is one thread's work from start to end, and its
        // result goes to its own slot, so the thread count changes nothing.
        std::vector<std::string> errors(mSelected.size());
        tbb::parallel_for(std::size_t(0), mSelected.size(), std::size_t(1), [&](std::size_t k) {
            try {
                runs[k] = runOne(k);
            } catch (const std::exception& e) {
                errors[k] = e.what();
            }
        });
        for (std::size_t k = 0; k < errors.size(); ++k) {
            if (!errors[k].empty()) caseFail(mSuite, mSuite.cases[mSelected[k]], "setup", errors[k]);
        }
    });
    return runs;
}

CaseRun Runner::runOne(std::size_t k) const
{
    const auto t0 = Clock::now();
    const Case& c = mSuite.cases[mSelected[k]];
    const Prepared& p = mImpl->cases[k];
    const Built& b = mImpl->volumes.at(mImpl->keys[k]);
    const haptic::Scene& scene = p.scene;

    const auto [entry, target] = casePath(mSuite, c, scene, b);
    const haptic::SceneInstance inst(scene, b.volume, *p.table, entry, target);

    const double speed = c.speedMmPerS.value_or(scene.speedMmPerS);
    const double pathLength = (inst.target() - inst.entry()).norm();
    const double depth = c.depthMm.value_or(scene.depthMm.value_or(pathLength));
    const haptic::InsertionScript script = c.script.empty()
        ? haptic::InsertionScript::constantSpeed(-scene.approachMm, depth, speed)
        : haptic::InsertionScript::load(c.script);
    auto model = makeModel(inst, c.strategy);
    const haptic::InsertionResult r = c.sweep
        ? runSweep(*model, *c.sweep, (inst.target() - inst.entry()).normalized(), scene.rateHz)
        : haptic::runInsertion(*model, script, scene.rateHz);

    CaseRun out;
    out.profile = profileOf(r, c.sampleMm);
    if (r.summary.bending) out.tipDeviationMm = r.summary.tipDeviationMm;
    for (const haptic::Layer& l : inst.layers()) {
        if (l.role != haptic::LayerRole::Air) out.layers.push_back({l.name, l.startMm, l.endMm});
    }

    // The fingerprint: version, case, scene, device, volume, and every tissue on the path.
    Inputs& in = out.inputs;
    putText(in, "voxhap.version", std::string(kVersion));
    putText(in, "case.scene", c.scene);
    putText(in, "case.strategy", c.strategy);
    putText(in, "case.entry", vecText(inst.entry()));
    putText(in, "case.target", vecText(inst.target()));
    if (c.sweep) {
        putText(in, "case.sweep.from", vecText(c.sweep->from));
        putText(in, "case.sweep.to", vecText(c.sweep->to));
        putNumber(in, "case.sweep.press_mm", c.sweep->pressMm, "mm");
        putNumber(in, "case.sweep.speed_mm_per_s", c.sweep->speedMmPerS, "mm/s");
        putNumber(in, "case.sweep.above_mm", c.sweep->aboveMm, "mm");
    } else if (c.script.empty()) {
        putNumber(in, "case.speed_mm_per_s", speed, "mm/s");
        putNumber(in, "case.depth_mm", depth, "mm");
    } else {
        putText(in, "case.script", c.script + " fnv1a " + fileDigest(c.script));
    }
    putNumber(in, "case.sample_mm", c.sampleMm, "mm");
    flattenScene(p.sceneJson, "scene", in);
    putText(in, "device.name", scene.device.name);
    putNumber(in, "device.max_force_N", scene.device.maxForceN, "N");
    putNumber(in, "device.max_continuous_force_N", scene.device.maxContinuousForceN, "N");
    putNumber(in, "device.max_stiffness_N_per_mm", scene.device.maxStiffnessNPerMm, "N/mm");
    putNumber(in, "device.max_damping_Ns_per_mm", scene.device.maxDampingNsPerMm, "N·s/mm");
    putNumber(in, "damping.cap_N", scene.terms.damping.capN, "N");
    putNumber(in, "damping.reference_speed_mm_per_s", scene.terms.damping.referenceSpeedMmPerS, "mm/s");
    recordVolume(p.volume, in);
    putText(in, "tissues.origin", p.table->origin());

    // Tissues that shape the profile: the layers' rows, and every label the path
    // crosses with the β the field gives it (what the damping integrates).
    std::set<std::string> used;
    for (const haptic::Layer& l : inst.layers()) {
        if (const volume::Tissue* t = l.label >= 0 ? p.table->find(l.label) : p.table->find(l.name)) {
            if (t->id != 0) used.insert(t->name);
        }
    }
    if (inst.field() && inst.field()->labels()) {
        std::vector<haptic::DampingPiece> pieces;
        const haptic::LabelTracer tracer(*inst.field());
        const Vec3d dir = (inst.target() - inst.entry()).normalized();
        const double reach = std::max(depth, pathLength);
        const auto runs = tracer.trace(inst.entry(), dir, reach, inst.field()->damping() ? &pieces : nullptr);
        for (const haptic::LabelRun& run : runs) {
            const volume::Tissue* t = p.table->find(run.label);
            if (!t || t->id == 0) continue;
            used.insert(t->name);
            const double mid = 0.5 * (run.startMm + run.endMm);
            for (const haptic::DampingPiece& piece : pieces) {
                if (piece.startMm <= mid && mid <= piece.endMm && !in.count(t->name + ".beta_used"))
                    putNumber(in, t->name + ".beta_used", piece.beta, "N·s/mm²");
            }
        }
    }
    for (const std::string& name : used) {
        const volume::Tissue& t = p.table->at(name);
        recordTissue(t, in);
        // A bending needle reads the foundation (physics.md §9.2); a straight one does
        // not, so the fingerprints of the other cases stay as they were.
        if (scene.terms.bending.on && t.foundationModulus)
            putNumber(in, t.name + ".foundation_modulus", t.foundationModulus->value, "N/mm²");
    }
    out.elapsedS = std::chrono::duration<double>(Clock::now() - t0).count();
    return out;
}

} // namespace voxhap::regress
