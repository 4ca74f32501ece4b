// SPDX-License-Identifier: Apache-2.0
/// @file PlanningBindings.cpp
/// @brief Python: segment a volume, plan a path (analyse given entries or
/// search them) with the report `voxhap plan --json` prints, and read plan files.

#include "python/Bindings.h"

#include "core/Errors.h"
#include "haptic/scene/Scene.h"
#include "planning/PlanFile.h"
#include "planning/Planner.h"
#include "planning/Report.h"
#include "planning/Search.h"
#include "segmentation/DistanceField.h"
#include "segmentation/Segmentation.h"
#include "volume/TissueTable.h"

#include <nlohmann/json.hpp>
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::python {

namespace {

using volume::Volume;

py::dict segmentReport(const segmentation::SegmentReport& r)
{
    py::dict d;
    d["method"] = r.method;
    d["seconds"] = r.seconds;
    d["imported_voxels"] = r.importedVoxels;
    d["distance_fields"] = r.distanceFields;
    d["notes"] = r.notes;
    d["body_width_mm"] = r.bodyWidthMm;
    d["torso_fraction"] = r.torsoFraction;
    py::list labels;
    for (const auto& l : r.labels) {
        py::dict x;
        x["id"] = l.id;
        x["name"] = l.name;
        x["voxels"] = l.voxels;
        x["ml"] = l.ml;
        x["min_mm"] = l.bounds[0];
        x["max_mm"] = l.bounds[1];
        labels.append(x);
    }
    d["labels"] = labels;
    return d;
}

/// As `voxhap plan` does: labels and distance fields the volume lacks are computed.
bool needsSegmentation(const Volume& v, const volume::TissueTable& table)
{
    bool anyField = false;
    for (const auto& t : table.tissues())
        anyField = anyField || (t.critical && v.derived(segmentation::distanceFieldName(t.name)));
    return !(v.has(volume::Channel::Label) && anyField);
}

py::object plan(const std::shared_ptr<Volume>& volume, std::optional<Vec3d> target, std::optional<Vec3d> entry,
    std::optional<std::vector<std::pair<Vec3d, Vec3d>>> paths, const std::string& sceneName, double speed,
    const Vec3d& reference, double maxAngleDeg, double maxLengthMm, double minClearanceMm, double marginMm,
    double stepDeg, int top, bool allowBone, std::optional<std::pair<Vec3d, Vec3d>> entryBox, const std::string& name)
{
    if (!target && !paths) throw ValueError("target is required (unless paths gives the entries and targets)");
    if (paths && (target || entry)) throw ValueError("paths gives entries and targets: target and entry do not apply");
    if (paths && paths->empty()) throw ValueError("paths: no (entry, target) pair");
    if (top < 1 || top > 1000) throw ValueError("top: must be within 1..1000");
    planning::SearchConstraints k;
    k.reference = reference;
    if (!(k.reference.norm() > 0)) throw ValueError("reference must not be zero");
    k.maxAngleDeg = maxAngleDeg;
    k.maxLengthMm = maxLengthMm;
    k.allowBoneObstacles = allowBone;
    if (entryBox) k.entryBox = planning::Box{entryBox->first, entryBox->second};
    const haptic::Scene scene = haptic::loadScene(sceneName);
    const volume::TissueTable& table = volume::TissueTable::builtin();
    if (target) {
        const auto b = volume->worldBounds();
        if ((target->array() < b[0].array()).any() || (target->array() > b[1].array()).any())
            throw ValueError("target lies outside the volume's bounds");
    }

    nlohmann::json report;
    {
        py::gil_scoped_release release;
        // The caller's volume stays as it was: a segmented copy (sharing the grids it keeps) is planned on.
        std::shared_ptr<const Volume> v = volume;
        if (needsSegmentation(*volume, table)) {
            auto copy = std::make_shared<Volume>(*volume);
            segmentation::SegmentOptions so;
            so.automatic = !copy->has(volume::Channel::Label);
            segmentation::segment(*copy, table, so);
            v = copy;
        }
        planning::PlanOptions po;
        po.speedMmPerS = speed;
        po.minClearanceMm = minClearanceMm;
        po.marginMm = marginMm;
        const planning::Planner planner(v, table, scene, po);
        report = planning::reportHeader(planner, name.empty() ? volume->metadata().source : name);
        std::vector<planning::TrajectoryReport> found;
        if (entry) {
            found.push_back(planner.analyze(*entry, *target));
        } else if (paths) {
            for (const auto& [e, t] : *paths) found.push_back(planner.analyze(e, t));
        } else {
            planning::SearchOptions so;
            so.stepDeg = stepDeg;
            so.top = top;
            const planning::SearchResult r = planning::search(planner, *target, k, so);
            found = r.ranked;
            report["search"] = planning::searchJson(planner, r, k, so);
            report["pareto"] = nlohmann::json::array();
            for (const auto& p : r.pareto) report["pareto"].push_back(planning::pathJson(p, 0));
        }
        report["paths"] = nlohmann::json::array();
        for (std::size_t i = 0; i < found.size(); ++i)
            report["paths"].push_back(planning::pathJson(found[i], int(i) + 1));
    }
    return toPython(report);
}

} // namespace

void bindPlanning(py::module_& m)
{
    m.def(
        "segment",
        [](Volume& v, std::optional<std::vector<std::string>> critical, double bandMm, bool automatic) {
            segmentation::SegmentOptions so;
            so.automatic = automatic;
            if (critical) so.critical = *critical;
            so.distanceBandMm = bandMm;
            py::gil_scoped_release release;
            const segmentation::SegmentReport r = segmentation::segment(v, volume::TissueTable::builtin(), so);
            py::gil_scoped_acquire acquire;
            return segmentReport(r);
        },
        py::arg("volume"), py::kw_only(), py::arg("critical") = std::nullopt, py::arg("band_mm") = 30.0,
        py::arg("automatic") = true,
        "Label the volume in place from hu (CT) or t1/intensity (MR) and add the sdf.<tissue> distance fields "
        "of the critical tissues, as `voxhap segment`; returns its report (method, labels with voxels, ml and "
        "bounds, distance_fields, notes)");

    m.def("plan", &plan, py::arg("volume"), py::arg("target") = std::nullopt, py::kw_only(),
        py::arg("entry") = std::nullopt, py::arg("paths") = std::nullopt, py::arg("scene") = "kyung",
        py::arg("speed") = 0.0, py::arg("reference") = Vec3d(0, 1, 0), py::arg("max_angle_deg") = 45.0,
        py::arg("max_length_mm") = 0.0, py::arg("min_clearance_mm") = 5.0, py::arg("margin_mm") = 20.0,
        py::arg("step_deg") = 2.0, py::arg("top") = 5, py::arg("allow_bone") = false,
        py::arg("entry_box") = std::nullopt, py::arg("name") = "",
        "Plan as `voxhap plan`: analyse entry -> target, or each (entry, target) of paths, or search entries "
        "to target around reference within max_angle_deg. The volume is segmented first (on a copy) when it "
        "lacks labels or distance fields. Returns the report `voxhap plan --json` prints (schema "
        "voxhap-plan-report/1): header, paths (ranked; segments, clearances, force profile, warnings, risk), "
        "and search and pareto when it searched.");

    m.def(
        "load_plan",
        [](const std::filesystem::path& file) {
            const planning::Plan plan = planning::loadPlan(file);
            py::list paths;
            for (const planning::PlannedPath& p : plan.paths) {
                py::dict d;
                d["name"] = p.name;
                d["entry"] = p.entry;
                d["target"] = p.target;
                if (p.needle) {
                    py::dict n;
                    n["tip"] = p.needle->tip;
                    n["direction"] = p.needle->direction;
                    n["length_mm"] = p.needle->lengthMm;
                    d["needle"] = n;
                }
                paths.append(d);
            }
            return paths;
        },
        py::arg("path"),
        "The planned paths of a plan file, as `voxhap view --plan` and `--guide` read them "
        "(planning/PlanFile.h): a plan.json (voxhap-plan/1), the report `voxhap plan` writes "
        "(voxhap-plan-report/1; path N is rank N) or 3D Slicer markups; a list of {name, entry, target[, "
        "needle: {tip, direction, length_mm}]} in LPS mm");
}

} // namespace voxhap::python
