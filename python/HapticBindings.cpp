// SPDX-License-Identifier: Apache-2.0
/// @file HapticBindings.cpp
/// @brief Python: the material field, shaft integration, scenes, one step of
/// the force model and a scripted insertion (simulate).

#include "python/HapticBindings.h"

#include "core/Errors.h"
#include "haptic/DeviceLimits.h"
#include "haptic/force/NeedleForceModel.h"
#include "haptic/materials/MaterialField.h"
#include "haptic/scene/Scene.h"
#include "haptic/scene/ScriptedInsertion.h"
#include "haptic/shaft/ShaftIntegration.h"
#include "volume/Grids.h"
#include "volume/TissueTable.h"

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::python {

namespace {

using haptic::MaterialField;
using volume::Volume;

/// A material field and the volume it was built from (for the arrays' box).
struct PyMaterialField {
    std::shared_ptr<const Volume> volume;
    std::unique_ptr<MaterialField> field;
};

/// An integrator and the field it reads, kept alive together.
struct PyIntegrator {
    std::shared_ptr<const PyMaterialField> field;
    std::unique_ptr<haptic::ShaftIntegrator> integrator;
    haptic::ShaftIntegral result; // reused: integrate() does not allocate
};

haptic::Strategy strategyOf(const std::string& s)
{
    if (s == "exact-voxel") return haptic::Strategy::ExactVoxel;
    if (s == "exact-trilinear") return haptic::Strategy::ExactTrilinear;
    if (s == "march-nearest") return haptic::Strategy::MarchNearest;
    if (s == "march-trilinear") return haptic::Strategy::MarchTrilinear;
    if (s == "profile") return haptic::Strategy::Profile;
    throw ValueError(
        "strategy: expected exact-voxel, exact-trilinear, march-nearest, march-trilinear or profile, got '" + s + "'");
}

std::string labelName(int id)
{
    const volume::Tissue* t = volume::TissueTable::builtin().find(id);
    return t ? t->name : std::to_string(id);
}

py::dict integralDict(const haptic::ShaftIntegral& r)
{
    py::dict d;
    d["length_mm"] = r.lengthMm;
    d["damping_integral"] = r.dampingIntegral;
    py::dict lengths, hits;
    if (r.labelsValid) {
        for (int i = 0; i < haptic::kMaxLabels; ++i) {
            if (r.labelLengthMm[std::size_t(i)] > 0) lengths[py::str(labelName(i))] = r.labelLengthMm[std::size_t(i)];
            if (std::isfinite(r.firstHitMm[std::size_t(i)])) hits[py::str(labelName(i))] = r.firstHitMm[std::size_t(i)];
        }
    }
    d["label_length_mm"] = lengths;
    d["first_hit_mm"] = hits;
    d["labels_valid"] = r.labelsValid;
    return d;
}

py::dict layerDict(const haptic::Layer& l)
{
    py::dict d;
    d["name"] = l.name;
    d["label"] = l.label;
    d["role"] = std::string(haptic::roleName(l.role));
    d["start_mm"] = l.startMm;
    d["end_mm"] = l.endMm;
    d["rigid"] = l.rigid;
    d["tents"] = l.tents;
    d["puncture_force_N"] = l.punctureForceN;
    d["cutting_force_N"] = l.cuttingForceN;
    d["coulomb_N"] = l.coulombN;
    d["viscous_Ns_per_mm2"] = l.viscousNsPerMm2;
    d["elastic"] = l.elastic;
    return d;
}

py::list layersList(const std::vector<haptic::Layer>& layers)
{
    py::list out;
    for (const auto& l : layers) out.append(layerDict(l));
    return out;
}

} // namespace

// Shared with ServoBindings.cpp (HapticBindings.h).
py::dict eventDict(const haptic::Event& e, const std::vector<haptic::Layer>& layers)
{
    py::dict d;
    d["type"] = std::string(haptic::eventName(e.type));
    d["time_s"] = e.timeS;
    d["depth_mm"] = e.depthMm;
    d["layer"] = e.layer >= 0 && std::size_t(e.layer) < layers.size()
        ? py::object(py::str(layers[std::size_t(e.layer)].name))
        : py::object(py::none());
    return d;
}

py::dict outputDict(const haptic::NeedleOutput& o, const std::vector<haptic::Layer>& layers)
{
    py::dict d;
    d["force"] = o.force;
    d["model_force"] = o.modelForce;
    d["axial_N"] = o.axialN;
    d["plunger_N"] = o.plungerN;
    d["speed_mm_per_s"] = o.speedMmPerS;
    d["depth_mm"] = o.tip.depthMm;
    const int layer = o.tip.currentLayer();
    d["layer"] = layer >= 0 && std::size_t(layer) < layers.size() ? py::object(py::str(layers[std::size_t(layer)].name))
                                                                  : py::object(py::none());
    d["in_body"] = o.tip.inBody;
    d["critical"] = o.critical;
    d["fault"] = o.fault;
    py::dict terms;
    terms["elastic"] = o.terms.elastic;
    terms["proxy"] = o.terms.proxy;
    terms["viscous"] = o.terms.viscous;
    terms["damping"] = o.terms.damping;
    terms["bone"] = o.terms.bone;
    terms["transient"] = o.terms.transient;
    terms["keep_direction"] = o.terms.keepDirection;
    terms["lateral"] = o.terms.lateral;
    d["terms"] = terms;
    py::list events;
    for (const haptic::Event& e : o.events) events.append(eventDict(e, layers));
    d["events"] = events;
    return d;
}

namespace {

haptic::Scene sceneOf(const std::string& nameOrPath) { return haptic::loadScene(nameOrPath); }

std::shared_ptr<PyScene> makeScene(const std::string& nameOrPath, std::shared_ptr<Volume> volume,
    std::optional<Vec3d> entry, std::optional<Vec3d> target)
{
    auto s = std::make_shared<PyScene>();
    s->volume = volume;
    const haptic::Scene scene = sceneOf(nameOrPath);
    py::gil_scoped_release release;
    s->instance = std::make_unique<haptic::SceneInstance>(
        scene, std::move(volume), volume::TissueTable::builtin(), entry, target);
    return s;
}

template <typename T>
py::array_t<T> column(const std::vector<haptic::InsertionRow>& rows, T (*get)(const haptic::InsertionRow&))
{
    py::array_t<T> a(py::ssize_t(rows.size()));
    T* p = a.mutable_data();
    for (std::size_t i = 0; i < rows.size(); ++i) p[i] = get(rows[i]);
    return a;
}

py::dict simulate(const std::shared_ptr<PyScene>& ps, std::optional<double> speed, std::optional<double> depth,
    std::optional<double> rate, std::optional<std::vector<std::pair<double, double>>> script)
{
    const haptic::SceneInstance& inst = *ps->instance;
    const haptic::Scene& scene = inst.scene();
    if (script && (speed || depth)) throw ValueError("script gives the motion: speed and depth do not apply");
    const double v = speed.value_or(scene.speedMmPerS);
    const double hz = rate.value_or(scene.rateHz);
    if (!(hz >= 1.0 && hz <= 1e6)) throw ValueError("rate: must be within 1..1e6 Hz");
    const double to = depth.value_or(scene.depthMm.value_or((inst.target() - inst.entry()).norm()));
    haptic::InsertionScript s;
    if (script) {
        s.knots = *script;
        for (std::size_t i = 1; i < s.knots.size(); ++i) {
            if (!(s.knots[i].first > s.knots[i - 1].first)) throw ValueError("script: times must increase");
        }
        if (s.knots.size() < 2) throw ValueError("script: give at least two (t_s, depth_mm) knots");
    } else {
        s = haptic::InsertionScript::constantSpeed(-scene.approachMm, to, v);
    }
    if (s.duration() * hz > 5e7) throw ValueError("rate and the insertion give more than 5e7 ticks");
    haptic::InsertionResult r;
    {
        py::gil_scoped_release release;
        auto model = inst.makeModel();
        r = haptic::runInsertion(*model, s, hz);
    }
    const auto& layers = inst.layers();
    py::dict d;
    d["time_s"] = column<double>(r.rows, [](const haptic::InsertionRow& x) { return x.timeS; });
    d["depth_mm"] = column<double>(r.rows, [](const haptic::InsertionRow& x) { return x.depthMm; });
    d["speed_mm_per_s"] = column<double>(r.rows, [](const haptic::InsertionRow& x) { return x.speedMmPerS; });
    d["force_N"] = column<double>(r.rows, [](const haptic::InsertionRow& x) { return x.force.norm(); });
    d["axial_N"] = column<double>(r.rows, [](const haptic::InsertionRow& x) { return x.axialN; });
    d["plunger_N"] = column<double>(r.rows, [](const haptic::InsertionRow& x) { return x.plungerN; });
    d["layer"] = column<int>(r.rows, [](const haptic::InsertionRow& x) { return x.layer; });
    py::array_t<double> force({py::ssize_t(r.rows.size()), py::ssize_t(3)});
    auto f = force.mutable_unchecked<2>();
    for (std::size_t i = 0; i < r.rows.size(); ++i) {
        for (int c = 0; c < 3; ++c) f(py::ssize_t(i), c) = r.rows[i].force[c];
    }
    d["force"] = force;
    py::list events;
    for (const haptic::Event& e : r.events) events.append(eventDict(e, layers));
    d["events"] = events;
    const haptic::InsertionSummary& sm = r.summary;
    const auto depthOrNone = [](double x) {
        return std::isfinite(x) ? py::object(py::float_(x)) : py::object(py::none());
    };
    py::dict summary;
    summary["skin_entry_mm"] = depthOrNone(sm.skinEntryMm);
    summary["loss_of_resistance_mm"] = depthOrNone(sm.lorMm);
    summary["dura_mm"] = depthOrNone(sm.duraMm);
    summary["bone_mm"] = depthOrNone(sm.boneMm);
    summary["breach_mm"] = depthOrNone(sm.breachMm);
    summary["pops"] = sm.pops;
    summary["bone_contacts"] = sm.boneContacts;
    summary["breaches"] = sm.breaches;
    summary["faults"] = sm.faults;
    summary["peak_model_N"] = sm.peakModelN;
    summary["peak_rendered_N"] = sm.peakRenderedN;
    summary["force_scale"] = scene.terms.renderScale; // the scene's uniform scale of what the device renders
    summary["peak_plunger_N"] = sm.peakPlungerN;
    summary["final_depth_mm"] = sm.finalDepthMm;
    summary["duration_s"] = sm.durationS;
    d["summary"] = summary;
    d["layers"] = layersList(layers);
    d["text"] = haptic::insertionSummaryText(r, layers);
    return d;
}

} // namespace

void bindHaptic(py::module_& m)
{
    py::class_<PyMaterialField, std::shared_ptr<PyMaterialField>>(m, "MaterialField",
        "The volume's image values turned into mechanics (physics.md sections 1.2, 1.3, 5): the damping grid "
        "beta [N s/mm^2], bone stiffness [N/mm] and per-label parameters")
        .def(py::init([](std::shared_ptr<Volume> v, bool damping, bool boneStiffness, const std::string& device) {
            auto f = std::make_shared<PyMaterialField>();
            haptic::MaterialOptions o;
            o.needs.damping = damping;
            o.needs.boneStiffness = boneStiffness;
            o.device = haptic::deviceLimits(device);
            f->volume = v;
            py::gil_scoped_release release;
            f->field = std::make_unique<MaterialField>(*v, volume::TissueTable::builtin(), o);
            return f;
        }),
            py::arg("volume"), py::kw_only(), py::arg("damping") = true, py::arg("bone_stiffness") = false,
            py::arg("device") = "touch")
        .def_property_readonly(
            "damping",
            [](const PyMaterialField& f) -> py::object {
                return f.field->damping() ? py::object(gridToArray(*f.volume, *f.field->damping())) : py::none();
            },
            "beta [N s/mm^2] as an array of the volume's shape, or None")
        .def_property_readonly(
            "bone_stiffness",
            [](const PyMaterialField& f) -> py::object {
                return f.field->boneStiffness() ? py::object(gridToArray(*f.volume, *f.field->boneStiffness()))
                                                : py::none();
            },
            "device-limited contact stiffness [N/mm] as an array, or None")
        .def_property_readonly("max_damping", [](const PyMaterialField& f) { return f.field->maxDamping(); })
        .def_property_readonly(
            "per_label",
            [](const PyMaterialField& f) {
                py::dict out;
                for (int i = 0; i < haptic::kMaxLabels; ++i) {
                    const haptic::LabelMaterial& l = f.field->perLabel()[std::size_t(i)];
                    if (!l.present) continue;
                    py::dict d;
                    d["id"] = i;
                    d["critical"] = l.critical;
                    d["rigid"] = l.rigid;
                    d["damping_Ns_per_mm2"] = l.dampingNsPerMm2;
                    d["puncture_force_N"] = l.punctureForceN;
                    d["cutting_force_N"] = l.cuttingForceN;
                    d["elasticity_N_per_mm"] = l.elasticityNPerMm;
                    d["friction_viscous_Ns_per_mm2"] = l.frictionViscousNsPerMm2;
                    d["friction_coulomb_N"] = l.frictionCoulombN;
                    out[py::str(labelName(i))] = d;
                }
                return out;
            },
            "per tissue name: the table's parameters in canonical units");

    py::class_<PyIntegrator, std::shared_ptr<PyIntegrator>>(m, "ShaftIntegrator",
        "Integrals along the needle shaft from entry to tip (physics.md 1.2, 7): the damping integral "
        "[N s/mm], the length in each tissue and each tissue's first hit [mm]")
        .def(py::init(
                 [](std::shared_ptr<PyMaterialField> f, const std::string& strategy, double stepMm, bool trackLabels) {
                     haptic::IntegratorOptions o;
                     o.strategy = strategyOf(strategy);
                     o.stepMm = stepMm;
                     o.trackLabels = trackLabels;
                     auto p = std::make_shared<PyIntegrator>();
                     p->integrator = haptic::makeIntegrator(*f->field, o);
                     p->field = std::move(f);
                     return p;
                 }),
            py::arg("field"), py::kw_only(), py::arg("strategy") = "exact-voxel", py::arg("step_mm") = 0.125,
            py::arg("track_labels") = true)
        .def_property_readonly("name", [](const PyIntegrator& p) { return p.integrator->name(); })
        .def(
            "integrate",
            [](PyIntegrator& p, const Vec3d& entry, const Vec3d& tip) {
                p.integrator->integrate(haptic::Segment{entry, tip}, p.result);
                return integralDict(p.result);
            },
            py::arg("entry"), py::arg("tip"),
            "{length_mm, damping_integral [N s/mm], label_length_mm, first_hit_mm, labels_valid}; the damping "
            "force at speed v [mm/s] is v times damping_integral");

    m.def("scene_names", &haptic::builtinSceneNames, "The built-in scenes (data/scenes/)");

    py::class_<PyScene, std::shared_ptr<PyScene>>(m, "Scene",
        "A scene (a built-in name or a scene JSON file) made ready to run on its own volume or phantom, or on "
        "the given volume: materials, the layers on its path and force models")
        .def(py::init(&makeScene), py::arg("scene"), py::arg("volume") = nullptr, py::kw_only(),
            py::arg("entry") = std::nullopt, py::arg("target") = std::nullopt)
        .def_property_readonly("name", [](const PyScene& s) { return s.instance->scene().name; })
        .def_property_readonly("description", [](const PyScene& s) { return s.instance->scene().description; })
        .def_property_readonly("entry", [](const PyScene& s) { return s.instance->entry(); })
        .def_property_readonly("target", [](const PyScene& s) { return s.instance->target(); })
        .def_property_readonly("speed_mm_per_s", [](const PyScene& s) { return s.instance->scene().speedMmPerS; })
        .def_property_readonly("rate_hz", [](const PyScene& s) { return s.instance->scene().rateHz; })
        .def_property_readonly("approach_mm", [](const PyScene& s) { return s.instance->scene().approachMm; })
        .def_property_readonly("device", [](const PyScene& s) { return s.instance->scene().device.name; })
        .def_property_readonly("layers", [](const PyScene& s) { return layersList(s.instance->layers()); })
        .def_property_readonly("volume",
            [](const PyScene& s) {
                // The instance's volume (the scene's phantom when none was given), shared read-only:
                // a copy of the Volume object, its grids shared.
                return std::make_shared<Volume>(s.instance->volume());
            })
        .def(
            "model",
            [](const std::shared_ptr<PyScene>& s) {
                auto p = std::make_shared<PyForceModel>();
                p->model = s->instance->makeModel();
                p->scene = s;
                return p;
            },
            "A fresh force model of the scene")
        .def("simulate", &simulate, py::kw_only(), py::arg("speed") = std::nullopt, py::arg("depth") = std::nullopt,
            py::arg("rate") = std::nullopt, py::arg("script") = std::nullopt,
            "A constant-speed insertion from approach_mm outside the entry to depth [mm] past it (default: the "
            "target), or a script of (t_s, depth_mm) knots, at rate [Hz]: as `voxhap simulate`. Returns numpy "
            "columns (time_s, depth_mm, speed_mm_per_s, force (n x 3), force_N, axial_N, plunger_N, layer), "
            "events, summary, layers and the summary text.");

    py::class_<PyForceModel, std::shared_ptr<PyForceModel>>(
        m, "ForceModel", "One scene's force pipeline (architecture.md 'The force pipeline'): one step per servo tick")
        .def(
            "step",
            [](PyForceModel& p, const Vec3d& tip, const Vec3d& direction, const Vec3d& velocity, double timeS,
                double dtS) {
                haptic::NeedleInput in;
                in.tip = tip;
                in.direction = direction;
                in.velocity = velocity;
                in.timeS = timeS;
                in.dtS = dtS;
                p.model->step(in, p.out);
                return outputDict(p.out, p.model->layers());
            },
            py::arg("tip"), py::arg("direction"), py::arg("velocity"), py::arg("time_s"), py::arg("dt_s") = 0.001,
            "One tick: tip [mm], shaft direction (hub to tip), tip velocity [mm/s], time [s] -> {force (rendered, "
            "N), model_force, axial_N (+ pushes out), depth_mm, layer, terms, events, ...}")
        .def("reset", [](PyForceModel& p) { p.model->reset(); })
        .def_property_readonly("layers", [](const PyForceModel& p) { return layersList(p.model->layers()); })
        .def_property_readonly("path_origin", [](const PyForceModel& p) { return p.model->path().origin; })
        .def_property_readonly("path_direction", [](const PyForceModel& p) { return p.model->path().direction; });

    m.def(
        "simulate",
        [](const std::string& scene, std::shared_ptr<Volume> volume, std::optional<Vec3d> entry,
            std::optional<Vec3d> target, std::optional<double> speed, std::optional<double> depth,
            std::optional<double> rate, std::optional<std::vector<std::pair<double, double>>> script) {
            return simulate(makeScene(scene, std::move(volume), entry, target), speed, depth, rate, script);
        },
        py::arg("scene"), py::arg("volume") = nullptr, py::kw_only(), py::arg("entry") = std::nullopt,
        py::arg("target") = std::nullopt, py::arg("speed") = std::nullopt, py::arg("depth") = std::nullopt,
        py::arg("rate") = std::nullopt, py::arg("script") = std::nullopt,
        "Scene(scene, volume, entry=, target=).simulate(speed=, depth=, rate=, script=) in one call");
}

} // namespace voxhap::python
