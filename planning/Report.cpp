// SPDX-License-Identifier: Apache-2.0
/// @file Report.cpp
#include "planning/Report.h"

#include "core/AtomicFile.h"
#include "core/BoundedRead.h"
#include "core/Errors.h"

namespace voxhap::planning {

namespace {
nlohmann::json point(const Vec3d& p) { return {p.x(), p.y(), p.z()}; }
/// JSON has no infinity: a depth never reached is null.
nlohmann::json depth(double d) { return std::isfinite(d) ? nlohmann::json(d) : nlohmann::json(); }
} // namespace

nlohmann::json pathJson(const TrajectoryReport& r, int rank)
{
    nlohmann::json j;
    j["rank"] = rank;
    j["entry"] = point(r.entry);
    j["target"] = point(r.target);
    j["length_mm"] = r.lengthMm;
    j["target_tissue"] = r.targetTissue;
    j["segments"] = nlohmann::json::array();
    for (const auto& s : r.segments) {
        j["segments"].push_back({{"tissue", s.tissue}, {"start_mm", s.startMm}, {"end_mm", s.endMm},
            {"length_mm", s.lengthMm()}, {"critical", s.critical}, {"rigid", s.rigid}});
    }
    j["clearances"] = nlohmann::json::array();
    for (const auto& c : r.clearances) {
        j["clearances"].push_back(
            {{"structure", c.tissue}, {"min_mm", c.minMm}, {"at_mm", c.atDepthMm}, {"at_least", c.beyondBand}});
    }
    j["min_clearance_mm"] = depth(r.minClearanceMm);
    j["nearest_structure"] = r.nearestStructure;
    j["bone"] = {{"entries", r.boneEntries}, {"obstacles", r.boneObstacles}, {"first_mm", depth(r.firstBoneMm)}};
    nlohmann::json f;
    f["speed_mm_per_s"] = r.speedMmPerS;
    f["peak_N"] = r.peakForceN;
    f["peak_depth_mm"] = r.peakDepthMm;
    f["contact_mm"] = depth(r.contactMm);
    f["depth_mm"] = nlohmann::json::array();
    f["force_N"] = nlohmann::json::array();
    for (const auto& s : r.force) f["depth_mm"].push_back(s.depthMm), f["force_N"].push_back(s.forceN);
    j["force"] = std::move(f);
    j["warnings"] = nlohmann::json::array();
    for (const auto& w : r.warnings) j["warnings"].push_back({{"code", w.code}, {"message", w.message}});
    j["risk"] = {{"total", r.risk.total}, {"breach", r.risk.breach}, {"too_short", r.risk.tooShort},
        {"bone_obstacles", r.risk.boneObstacles}, {"over_force", r.risk.overForce}, {"proximity", r.risk.proximity},
        {"length", r.risk.length}, {"force", r.risk.force}};
    if (r.deflection) { // a bending needle (physics.md §9.6)
        const auto choice = [](const BevelChoice& c) {
            return nlohmann::json{{"bevel_orientation_deg", c.orientationDeg}, {"turn_depth_mm", depth(c.turnDepthMm)},
                {"tip_deviation_mm", c.tipDeviationMm}, {"tip_to_target_mm", c.tipToTargetMm}};
        };
        nlohmann::json d;
        d["best"] = choice(r.deflection->best);
        d["without_turn"] = nlohmann::json::array();
        for (const auto& c : r.deflection->tried) {
            if (!std::isfinite(c.turnDepthMm)) d["without_turn"].push_back(choice(c));
        }
        d["choices_tried"] = r.deflection->tried.size();
        d["bent_shaft"] = nlohmann::json::array();
        for (const Vec3d& p : r.deflection->bentShaft) d["bent_shaft"].push_back(point(p));
        j["deflection"] = std::move(d);
    }
    return j;
}

nlohmann::json reportHeader(const Planner& p, const std::string& volumeName)
{
    const auto& s = p.scene();
    return {{"schema", kReportSchema}, {"volume", volumeName}, {"scene", s.name},
        {"model", haptic::layerModelName(s.recipe.model)}, {"speed_mm_per_s", p.speedMmPerS()},
        {"needle_mm", s.needle.lengthMm}, {"device", {{"name", s.device.name}, {"max_force_N", s.device.maxForceN}}},
        {"min_clearance_mm", p.options().minClearanceMm}, {"margin_mm", p.options().marginMm},
        {"distance_band_mm", p.distanceBandMm()}, {"critical_structures", p.criticalStructures()},
        {"risk_formula", kRiskFormula}};
}

nlohmann::json searchJson(
    const Planner& planner, const SearchResult& found, const SearchConstraints& k, const SearchOptions& options)
{
    const SearchCounts& c = found.counts;
    return {{"directions", c.directions}, {"analysed", c.analysed}, {"feasible", c.feasible},
        {"seconds", found.seconds}, {"candidates_per_s", found.seconds > 0 ? double(c.analysed) / found.seconds : 0.0},
        {"rejected",
            {{"no_skin_exit", c.noSkinExit}, {"not_skin", c.notSkin}, {"outside_box", c.outsideBox},
                {"critical_breach", c.breach}, {"clearance", c.clearance}, {"bone", c.bone}, {"too_long", c.tooLong}}},
        {"constraints",
            {{"reference", {k.reference.x(), k.reference.y(), k.reference.z()}}, {"max_angle_deg", k.maxAngleDeg},
                {"max_length_mm", found.maxLengthMm}, {"min_clearance_mm", planner.options().minClearanceMm},
                {"step_deg", options.stepDeg}}}};
}

void writeReport(const nlohmann::json& report, const std::filesystem::path& file)
{
    writeStreamAtomically(file, [&](std::ostream& os) { os << report.dump(2) << '\n'; });
}

std::vector<MarkupLine> parseReportPaths(std::string_view json, const std::string& origin)
{
    const nlohmann::json j = parseJsonText(json, origin); // any nlohmann::json exception, on one line
    const auto fail = [&](const std::string& field, const std::string& why) {
        throw ValueError(origin + ": " + field + ": " + why);
    };
    if (!j.is_object()) fail("schema", "not a planning report (a JSON object expected)");
    if (!j.contains("schema") || j["schema"] != kReportSchema)
        fail("schema", std::string("must be \"") + kReportSchema + "\"");
    if (!j.contains("paths") || !j["paths"].is_array()) fail("paths", "must be an array");
    std::vector<MarkupLine> lines;
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
        lines.push_back({"path " + std::to_string(i + 1), pts[0], pts[1]});
    }
    return lines;
}

std::vector<MarkupLine> loadPlannedLines(const std::filesystem::path& file)
{
    const std::string text = readBoundedFile(file, "plan file"); // regular, at most 16 MiB
    const nlohmann::json j = parseJsonText(text, file.string());
    if (j.is_object() && j.contains("markups")) return parseMarkups(text, file.string());
    if (j.is_object() && j.contains("schema")) return parseReportPaths(text, file.string());
    throw ValueError(file.string() + ": neither a planning report (\"schema\": \"" + kReportSchema +
        "\") nor 3D Slicer markups (\"markups\")");
}

} // namespace voxhap::planning
