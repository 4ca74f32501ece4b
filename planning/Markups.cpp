// SPDX-License-Identifier: Apache-2.0
/// @file Markups.cpp
#include "planning/Markups.h"

#include "core/AtomicFile.h"
#include "core/BoundedRead.h"
#include "core/Errors.h"

#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

namespace voxhap::planning {

namespace {

using Json = nlohmann::json;

Json controlPoint(int id, const std::string& label, const Vec3d& p)
{
    return {{"id", std::to_string(id)}, {"label", label}, {"description", ""}, {"associatedNodeID", ""},
        {"position", {p.x(), p.y(), p.z()}},
        {"orientation", {-1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0}}, // identity in RAS, as Slicer writes in LPS
        {"selected", true}, {"locked", true}, {"visibility", true}, {"positionStatus", "defined"}};
}

} // namespace

std::string markupsJson(const std::vector<MarkupLine>& lines)
{
    Json doc;
    doc["@schema"] = kMarkupsSchema;
    doc["markups"] = Json::array();
    for (const auto& l : lines) {
        Json m;
        m["type"] = "Line";
        m["name"] = l.name;
        m["coordinateSystem"] = "LPS";
        m["coordinateUnits"] = "mm";
        m["locked"] = true;
        m["fixedNumberOfControlPoints"] = true;
        m["labelFormat"] = "%N-%d";
        m["lastUsedControlPointNumber"] = 2;
        m["controlPoints"] = {controlPoint(1, "entry", l.entry), controlPoint(2, "target", l.target)};
        m["measurements"] = {{{"name", "length"}, {"enabled", true}, {"value", (l.target - l.entry).norm()},
            {"units", "mm"}, {"printFormat", "%-#4.4g%s"}}};
        m["display"] = {{"visibility", true}, {"opacity", 1.0}, {"color", {0.4, 1.0, 1.0}},
            {"selectedColor", {1.0, 0.5, 0.5}}, {"propertiesLabelVisibility", true}, {"pointLabelsVisibility", true},
            {"textScale", 3.0}, {"glyphType", "Sphere3D"}, {"glyphScale", 1.0}, {"glyphSize", 5.0},
            {"useGlyphScale", true}, {"lineThickness", 0.2}};
        doc["markups"].push_back(std::move(m));
    }
    return doc.dump(4) + "\n";
}

void writeMarkups(const std::vector<MarkupLine>& lines, const std::filesystem::path& file)
{
    const std::string text = markupsJson(lines);
    writeStreamAtomically(file, [&](std::ostream& os) { os << text; });
}

std::vector<MarkupLine> parseMarkups(std::string_view json, const std::string& origin)
{
    const Json j = parseJsonText(json, origin); // any nlohmann::json exception, on one line
    const auto fail = [&](const std::string& field, const std::string& why) {
        throw ValueError(origin + ": " + field + ": " + why);
    };
    if (!j.is_object() || !j.contains("markups") || !j["markups"].is_array()) fail("markups", "must be an array");
    std::vector<MarkupLine> lines;
    try {
        for (std::size_t m = 0; m < j["markups"].size(); ++m) {
            const Json& mk = j["markups"][m];
            const std::string at = "markups[" + std::to_string(m) + "]";
            if (!mk.is_object() || mk.value("type", "") != "Line") continue;
            const std::string system = mk.value("coordinateSystem", "LPS");
            if (system != "LPS" && system != "RAS") fail(at + ".coordinateSystem", "must be LPS or RAS");
            if (mk.contains("coordinateUnits") && mk["coordinateUnits"] != "mm")
                fail(at + ".coordinateUnits", "must be mm");
            if (!mk.contains("controlPoints") || !mk["controlPoints"].is_array() || mk["controlPoints"].size() != 2) {
                fail(at + ".controlPoints", "a Line needs exactly two control points");
            }
            Vec3d pts[2];
            for (std::size_t c = 0; c < 2; ++c) {
                const Json& cp = mk["controlPoints"][c];
                const Json pos = cp.is_object() && cp.contains("position") ? cp["position"] : Json();
                const std::string field = at + ".controlPoints[" + std::to_string(c) + "].position";
                if (!pos.is_array() || pos.size() != 3) fail(field, "must be [x, y, z] in mm");
                for (int k = 0; k < 3; ++k) {
                    if (!pos[std::size_t(k)].is_number()) fail(field, "must be [x, y, z] in mm");
                    pts[c][k] = pos[std::size_t(k)].get<double>();
                }
                if (!pts[c].allFinite()) fail(field, "must be finite");
                if (system == "RAS") pts[c].x() = -pts[c].x(), pts[c].y() = -pts[c].y(); // RAS → LPS
            }
            if ((pts[1] - pts[0]).norm() < 1e-6) fail(at + ".controlPoints", "the two points coincide");
            lines.push_back({mk.value("name", "line " + std::to_string(lines.size() + 1)), pts[0], pts[1]});
        }
    } catch (const Json::exception& e) { // a field of the wrong type
        throw ValueError(origin + ": " + e.what());
    }
    if (lines.empty()) fail("markups", "no Line markup with two control points");
    return lines;
}

std::vector<MarkupLine> loadMarkups(const std::filesystem::path& file)
{
    return parseMarkups(readBoundedFile(file, "markups file"), file.string()); // regular, at most 16 MiB
}

} // namespace voxhap::planning
