// SPDX-License-Identifier: Apache-2.0
/// @file Insertion.h
/// @brief A scripted insertion through a force model at a fixed servo rate: the
/// engine of `voxhap simulate` and of the preset regression tests.
#pragma once

#include "haptic/Procedure.h"
#include "haptic/force/NeedleForceModel.h"

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace voxhap::haptic {

/// @brief Tip depth along the path over time, piecewise linear between knots.
struct InsertionScript {
    std::vector<std::pair<double, double>> knots; ///< (t [s], depth [mm]), t increasing
    /// The needle's roll at each knot [deg], or empty: a script without the column
    /// leaves the bevel as the scene sets it (a bending needle turns with it, physics.md §9.3).
    std::vector<double> rollsDeg;

    /// @brief From @p fromMm to @p toMm at @p speedMmPerS. @throw ValueError on a non-positive speed
    static InsertionScript constantSpeed(double fromMm, double toMm, double speedMmPerS);
    /// @brief A CSV file of "t_s,depth_mm" rows, or "t_s,depth_mm,roll_deg" rows on
    /// every line (a header line is allowed).
    /// @throw IoError, ValueError naming the file and line
    static InsertionScript load(const std::filesystem::path& file);
    double duration() const { return knots.empty() ? 0.0 : knots.back().first; }
    double depthAt(double t) const;
    double speedAt(double t) const; ///< [mm/s], the slope of the segment holding t
    /// [rad], linear between knots (a turn takes the time between its rows); NaN without a roll column
    double rollAt(double t) const;
};

/// @brief One tick of the record.
struct InsertionRow {
    double timeS = 0, depthMm = 0, speedMmPerS = 0;
    Vec3d force{0, 0, 0}; ///< rendered [N]
    double axialN = 0;    ///< model resistance along the path [N]
    double plungerN = 0;
    int layer = -1; ///< current layer
    LayerState state = LayerState::Intact;
    bool critical = false, fault = false;
    int firstEvent = 0, eventCount = 0; ///< into InsertionResult::events
};

struct InsertionSummary {
    double skinEntryMm = kNoLimit, lorMm = kNoLimit, duraMm = kNoLimit, boneMm = kNoLimit, breachMm = kNoLimit;
    int pops = 0, boneContacts = 0, breaches = 0, faults = 0;
    double peakModelN = 0, peakRenderedN = 0, peakPlungerN = 0;
    double finalDepthMm = 0, durationS = 0;
    // The device's peak and I²t limits (§6.3): how often they started cutting the
    // force (ForceLimited events), from where, for how many ticks, and by how much.
    int forceLimits = 0;
    long limitedTicks = 0;
    double firstLimitMm = kNoLimit, maxLimitedN = 0;
    bool guidance = false;    ///< the guidance term ran (Guidance.h)
    double peakGuidanceN = 0; ///< its largest pull [N]
    double maxOffsetMm = 0;   ///< the tip's largest distance from the planned line [mm]
    bool bending = false;     ///< the needle bends (physics.md §9)
    /// The bent tip's distance from the straight line of the path at the last tick,
    /// and the largest over the run [mm].
    double tipDeviationMm = 0, maxTipDeviationMm = 0;
};

struct InsertionResult {
    std::vector<InsertionRow> rows;
    std::vector<Event> events;
    InsertionSummary summary;
    ProcedureOutcome outcome;     ///< under the rule runInsertion was given
    std::vector<Vec3d> bentShaft; ///< a bending needle's shaft at the last tick, hub to tip [mm, LPS]; else empty
};

/// @brief Drive @p model along its path by @p script at @p rateHz (the tip on the
/// path, the needle along it), judging the outcome by @p success against @p target.
InsertionResult runInsertion(NeedleForceModel& model, const InsertionScript& script, double rateHz,
    const SuccessCriteria& success = {}, std::optional<Vec3d> target = std::nullopt);

/// @brief CSV: t_s, depth_mm, speed_mm_per_s, fx_N, fy_N, fz_N, force_N, axial_model_N,
/// plunger_N, state, layer, events. Written to a temporary file, then renamed.
void writeInsertionCsv(const InsertionResult& r, const std::vector<Layer>& layers, const std::filesystem::path& file);

/// @brief The human summary: skin entry, pops, loss of resistance, dura, bone, peaks.
std::string insertionSummaryText(const InsertionResult& r, const std::vector<Layer>& layers);

} // namespace voxhap::haptic
