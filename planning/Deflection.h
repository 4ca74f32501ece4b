// SPDX-License-Identifier: Apache-2.0
/// @file Deflection.h
/// @brief Where a bending needle's tip ends on a straight plan (physics.md §9.6):
/// the needle pushed along the planned line through the volume's tissue (the
/// beam of haptic/beam/ on the label foundation), for each bevel orientation and
/// each depth of one half turn, and the choice that ends nearest the target.
#pragma once

#include "planning/Trajectory.h"

#include <vector>

namespace voxhap::planning {

class Planner;

/// @brief How finely the prediction runs, and for how many paths (physics.md §9.6).
struct DeflectionOptions {
    /// Hub advance per solve [mm] [chosen: the cut front's trapezoid rule keeps the
    /// tip's path within 0.02 mm of its converged one at 1 mm steps, 80 mm into
    /// muscle (physics.md §9.3)]
    double stepMm = 1.0;
    /// Needle per beam element [mm] [chosen: twice the servo's 1 mm, half its
    /// solve; λh ≤ 0.15 in muscle for 18–22 G, where the elements' error goes as (λh)⁴]
    double nodeSpacingMm = 2.0;
    double turnEveryMm = 5.0;  ///< depths of the half turn tried [mm] (every 5 mm)
    double turnFromMm = 5.0;   ///< the first of them [mm]
    std::size_t maxPaths = 10; ///< only the first paths (a search's best ranked) are predicted
};

/// @brief Predict the deflection of @p path (entry → target) under the planner's
/// scene; nothing when its needle does not bend (scene terms.bending off).
/// @throw ValueError on a needle the beam refuses (BeamParams::fromNeedle)
std::optional<DeflectionPrediction> predictDeflection(
    const Planner& planner, const TrajectoryReport& path, const DeflectionOptions& options = {});

/// @brief predictDeflection for the first DeflectionOptions::maxPaths of @p paths, in
/// parallel; fills their `deflection` (the others keep none).
void predictDeflections(
    const Planner& planner, std::vector<TrajectoryReport>& paths, const DeflectionOptions& options = {});

} // namespace voxhap::planning
