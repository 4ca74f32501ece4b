// SPDX-License-Identifier: Apache-2.0
/// @file Plan.cpp
#include "render/Plan.h"

#include "volume/AtomicFile.h"
#include "volume/Errors.h"
#include "volume/JsonFields.h"

#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

namespace voxhap::render {

namespace {

using Json = nlohmann::json;
using Fields = volume::JsonFields;

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
    return pose;
}

Plan parseVoxhapPlan(Fields& top, const std::string& origin)
{
    if (top.string("schema", "") != "voxhap-plan/1") top.fail("schema", "must be \"voxhap-plan/1\"");
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

/// 3D Slicer markups: only what a Line needs is read; the many display and
/// measurement fields Slicer writes are passed over.
Plan parseSlicerMarkups(const Json& j, const std::string& origin)
{
    const auto fail = [&](const std::string& field, const std::string& why) {
        throw ValueError(origin + ": " + field + ": " + why);
    };
    if (!j.contains("markups") || !j["markups"].is_array()) fail("markups", "must be an array");
    Plan plan;
    for (std::size_t m = 0; m < j["markups"].size(); ++m) {
        const Json& mk = j["markups"][m];
        const std::string at = "markups[" + std::to_string(m) + "]";
        if (!mk.is_object() || mk.value("type", "") != "Line") continue;
        const std::string system = mk.value("coordinateSystem", "LPS");
        if (system != "LPS" && system != "RAS") fail(at + ".coordinateSystem", "must be LPS or RAS");
        if (mk.contains("coordinateUnits") && mk["coordinateUnits"] != "mm") fail(at + ".coordinateUnits", "must be mm");
        if (!mk.contains("controlPoints") || !mk["controlPoints"].is_array() || mk["controlPoints"].size() != 2) {
            fail(at + ".controlPoints", "a Line needs exactly two control points");
        }
        Vec3d pts[2];
        for (std::size_t c = 0; c < 2; ++c) {
            const Json& pos = mk["controlPoints"][c].contains("position") ? mk["controlPoints"][c]["position"] : Json();
            const std::string field = at + ".controlPoints[" + std::to_string(c) + "].position";
            if (!pos.is_array() || pos.size() != 3) fail(field, "must be [x, y, z] in mm");
            for (int k = 0; k < 3; ++k) {
                if (!pos[std::size_t(k)].is_number()) fail(field, "must be [x, y, z] in mm");
                pts[c][k] = pos[std::size_t(k)].get<double>();
            }
            if (!pts[c].allFinite()) fail(field, "must be finite");
            if (system == "RAS") pts[c].x() = -pts[c].x(), pts[c].y() = -pts[c].y();
        }
        PlannedPath path;
        path.name = mk.value("name", "line " + std::to_string(plan.paths.size() + 1));
        path.entry = pts[0];
        path.target = pts[1];
        if ((path.target - path.entry).norm() < 1e-6) fail(at + ".controlPoints", "the two points coincide");
        plan.paths.push_back(std::move(path));
    }
    if (plan.paths.empty()) fail("markups", "no Line markup with two control points");
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
    if (j.is_object() && j.contains("markups")) {
        try {
            return parseSlicerMarkups(j, origin);
        } catch (const Json::exception& e) { // a field of the wrong type
            throw ValueError(origin + ": " + e.what());
        }
    }
    Fields top(j, origin, "");
    return parseVoxhapPlan(top, origin);
}

Plan loadPlan(const std::filesystem::path& file)
{
    std::ifstream in(file);
    if (!in) throw IoError(file.string() + ": cannot open the plan");
    std::ostringstream text;
    text << in.rdbuf();
    return parsePlan(text.str(), file.string());
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
        }
        paths.push_back(std::move(j));
    }
    return Json{{"schema", "voxhap-plan/1"}, {"paths", paths}}.dump(2) + "\n";
}

void savePlan(const Plan& plan, const std::filesystem::path& file)
{
    const std::string text = planJson(plan);
    volume::writeStreamAtomically(file, [&](std::ostream& out) { out << text; });
}

} // namespace voxhap::render
