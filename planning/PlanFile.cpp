// SPDX-License-Identifier: Apache-2.0
/// @file PlanFile.cpp
/// @brief The three plan formats read, told apart by content; voxhap-plan/1 written.
#include "planning/PlanFile.h"

#include "core/AtomicFile.h"
#include "core/BoundedRead.h"
#include "core/Errors.h"
#include "core/JsonFields.h"
#include "planning/Markups.h"

#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

namespace voxhap::planning {

namespace {

using Json = nlohmann::json;
using Fields = JsonFields;

Vec3d requiredPoint(Fields& f, const std::string& key)
{
    if (!f.has(key)) f.fail(key, "missing ([x, y, z] in mm)");
    return f.vec3(key);
}

/// Each element of the array @p key as an object, with its path for errors.
template <typename Each>
void forEachObject(Fields& f, const std::string& key, const std::string& origin, const std::string& path, Each&& each)
{
    if (!f.has(key)) f.fail(key, "missing");
    const Json& arr = f.raw(key);
    if (!arr.is_array()) f.fail(key, "must be an array");
    for (std::size_t i = 0; i < arr.size(); ++i) {
        Fields item(arr[i], origin, path + key + "[" + std::to_string(i) + "]");
        each(item);
    }
}

NeedlePose parseNeedle(Fields n)
{
    NeedlePose pose;
    pose.tip = requiredPoint(n, "tip");
    const Vec3d d = requiredPoint(n, "direction");
    if (!(d.norm() > 1e-9)) n.fail("direction", "must not be zero");
    pose.direction = d.normalized();
    pose.lengthMm = n.number("length_mm", pose.lengthMm, true);
    if (n.has("shaft")) { // a bending needle's polyline, hub to tip
        const Json& s = n.raw("shaft");
        if (!s.is_array() || s.size() < 2) n.fail("shaft", "must be a list of at least two [x, y, z] points in mm");
        for (const Json& q : s) {
            if (!q.is_array() || q.size() != 3 || !q[0].is_number() || !q[1].is_number() || !q[2].is_number())
                n.fail("shaft", "must be a list of [x, y, z] points in mm");
            const Vec3d p(q[0].get<double>(), q[1].get<double>(), q[2].get<double>());
            if (!p.allFinite()) n.fail("shaft", "points must be finite");
            pose.shaft.push_back(p);
        }
    }
    return pose;
}

Plan parseVoxhapPlan(Fields& top, const std::string& origin)
{
    if (top.string("schema", "") != kPlanSchema) {
        top.fail("schema",
            std::string("must be \"") + kPlanSchema + "\" or \"" + kReportSchema + "\" (or 3D Slicer markups)");
    }
    Plan plan;
    forEachObject(top, "paths", origin, "", [&](Fields& p) {
        PlannedPath path;
        path.name = p.string("name", "path " + std::to_string(plan.paths.size() + 1));
        path.entry = requiredPoint(p, "entry");
        path.target = requiredPoint(p, "target");
        if ((path.target - path.entry).norm() < 1e-6) p.fail("target", "coincides with the entry");
        if (p.has("needle")) path.needle = parseNeedle(p.sub("needle"));
        plan.paths.push_back(std::move(path));
    });
    if (plan.paths.empty()) top.fail("paths", "must hold at least one path");
    return plan;
}

/// voxhap-plan-report/1: only each path's entry and target are read (a report
/// holds much more per path), in rank order; no paths is a search that found none.
Plan parseReportPlan(const nlohmann::json& j, const std::string& origin)
{
    const auto fail = [&](const std::string& field, const std::string& why) {
        throw ValueError(origin + ": " + field + ": " + why);
    };
    if (!j.contains("paths") || !j["paths"].is_array()) fail("paths", "must be an array");
    Plan plan;
    for (std::size_t i = 0; i < j["paths"].size(); ++i) {
        const nlohmann::json& path = j["paths"][i];
        const std::string at = "paths[" + std::to_string(i) + "]";
        if (!path.is_object()) fail(at, "must be an object");
        Vec3d pts[2];
        const char* keys[2] = {"entry", "target"};
        for (int c = 0; c < 2; ++c) {
            const std::string field = at + "." + keys[c];
            const nlohmann::json p = path.contains(keys[c]) ? path[keys[c]] : nlohmann::json();
            if (!p.is_array() || p.size() != 3) fail(field, "must be [x, y, z] in mm");
            for (int k = 0; k < 3; ++k) {
                if (!p[std::size_t(k)].is_number()) fail(field, "must be [x, y, z] in mm");
                pts[c][k] = p[std::size_t(k)].get<double>();
            }
            if (!pts[c].allFinite()) fail(field, "must be finite");
        }
        if ((pts[1] - pts[0]).norm() < 1e-6) fail(at, "entry and target coincide");
        plan.paths.push_back({"path " + std::to_string(i + 1), pts[0], pts[1], std::nullopt});
    }
    return plan;
}

} // namespace

Plan parsePlan(std::string_view json, const std::string& origin)
{
    Json j;
    try {
        j = Json::parse(json.begin(), json.end());
    } catch (const Json::parse_error& e) {
        throw ValueError(origin + ": not valid JSON (" + std::string(e.what()) + ")");
    }
    if (j.is_object() && j.contains("markups")) { // 3D Slicer markups (Markups.h)
        Plan plan;
        for (auto& l : parseMarkups(json, origin)) plan.paths.push_back({l.name, l.entry, l.target, std::nullopt});
        return plan;
    }
    if (j.is_object() && j.contains("schema") && j["schema"] == kReportSchema) return parseReportPlan(j, origin);
    Fields top(j, origin, "");
    return parseVoxhapPlan(top, origin);
}

Plan loadPlan(const std::filesystem::path& file)
{
    // A regular file within the 16 MiB limit of text inputs: not a FIFO, /dev/zero or a huge file.
    return parsePlan(readBoundedFile(file, "plan"), file.string());
}

std::string planJson(const Plan& plan)
{
    const auto point = [](const Vec3d& p) { return Json::array({p.x(), p.y(), p.z()}); };
    Json paths = Json::array();
    for (const PlannedPath& p : plan.paths) {
        Json j = {{"entry", point(p.entry)}, {"target", point(p.target)}};
        if (!p.name.empty()) j["name"] = p.name;
        if (p.needle) {
            j["needle"] = {{"tip", point(p.needle->tip)}, {"direction", point(p.needle->direction)},
                {"length_mm", p.needle->lengthMm}};
            if (!p.needle->shaft.empty()) {
                Json shaft = Json::array();
                for (const Vec3d& q : p.needle->shaft) shaft.push_back(point(q));
                j["needle"]["shaft"] = std::move(shaft);
            }
        }
        paths.push_back(std::move(j));
    }
    return Json{{"schema", kPlanSchema}, {"paths", paths}}.dump(2) + "\n";
}

void savePlan(const Plan& plan, const std::filesystem::path& file)
{
    const std::string text = planJson(plan);
    writeStreamAtomically(file, [&](std::ostream& out) { out << text; });
}

} // namespace voxhap::planning
