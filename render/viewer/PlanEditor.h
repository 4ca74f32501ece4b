// SPDX-License-Identifier: Apache-2.0
/// @file PlanEditor.h
/// @brief What the viewer's clicks mean, as a state machine free of any view:
/// a tool is chosen by key, and each click (a world point picked on a slice)
/// advances that tool.
///
/// - Navigate: a click moves the crosshair (and so the other slices) there.
/// - Plan: the first click is the entry, the second the target; the path is
///   then complete and replaces the previous one drawn in the viewer. A third
///   click starts a new entry while the last complete path stays in the plan.
/// - Distance: two clicks measure a distance; a third starts anew.
/// - Angle: four clicks give two segments and the angle between them.
#pragma once

#include "planning/PlanFile.h"
#include "render/viewer/Measurement.h"

#include <optional>
#include <string>
#include <vector>

namespace voxhap::render {

enum class Tool {
    Navigate,
    Plan,
    Distance,
    Angle
};

std::string_view toolName(Tool t); ///< "navigate", "plan", "distance", "angle"

class PlanEditor {
public:
    /// @param initial paths loaded with --plan: kept and drawn; the viewer's own
    /// path is appended after them as "viewer"
    explicit PlanEditor(planning::Plan initial = {});

    void setTool(Tool t);
    Tool tool() const { return mTool; }

    /// @brief A click at world point @p w [mm, LPS] with the current tool.
    /// @return the new crosshair position if the tool is Navigate
    std::optional<Vec3d> click(const Vec3d& w);
    /// @brief Forget the measurements and any half-made path.
    void clearMeasurements();

    /// @brief The loaded paths plus the one made here (if complete).
    const planning::Plan& plan() const { return mPlan; }
    /// @brief True once the viewer's path has an entry and a target.
    bool hasEditedPath() const { return mEdited.has_value(); }
    /// @brief An entry clicked but no target yet.
    const std::optional<Vec3d>& pendingEntry() const { return mPendingEntry; }
    /// @brief The points of the distance or angle being picked (0..3).
    const std::vector<Vec3d>& pendingPoints() const { return mPoints; }
    /// @brief The last complete distance measurement.
    const std::optional<Segment>& distance() const { return mDistance; }
    /// @brief The two segments of the last complete angle measurement.
    const std::optional<std::pair<Segment, Segment>>& angle() const { return mAngle; }
    /// @brief One line on the tool's state, for the status bar.
    std::string status() const;

private:
    Tool mTool = Tool::Navigate;
    planning::Plan mPlan;
    std::optional<std::size_t> mEdited; ///< index of the viewer's path in mPlan
    std::optional<Vec3d> mPendingEntry;
    std::vector<Vec3d> mPoints;
    std::optional<Segment> mDistance;
    std::optional<std::pair<Segment, Segment>> mAngle;
};

} // namespace voxhap::render
