// SPDX-License-Identifier: Apache-2.0
/// @file Report.cpp
#include "planning/Report.h"

#include "core/AtomicFile.h"

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

} // namespace voxhap::planning
