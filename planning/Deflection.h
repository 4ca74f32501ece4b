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

/// @brief How finely the prediction runs.
struct DeflectionOptions {
    /// Hub advance per solve [mm] over the first fineDepthMm, where the deflection is
    /// made and the result depends on the step (physics.md §9.6) [chosen: within 1 %
    /// of the servo's 0.01 mm ticks on the torso phantom]
    double fineStepMm = 0.02;
    double fineDepthMm = 15.0; ///< [mm]
    double stepMm = 0.25;      ///< hub advance per solve beyond it [mm] [chosen: a quarter of the node spacing]
    double turnEveryMm = 5.0;  ///< depths of the half turn tried [mm] (every 5 mm)
    double turnFromMm = 5.0;   ///< the first of them [mm]
};

/// @brief Predict the deflection of @p path (entry → target) under the planner's
/// scene; nothing when its needle does not bend (scene terms.bending off).
/// @throw ValueError on a needle the beam refuses (BeamParams::fromNeedle)
std::optional<DeflectionPrediction> predictDeflection(
    const Planner& planner, const TrajectoryReport& path, const DeflectionOptions& options = {});

/// @brief predictDeflection for each of @p paths, in parallel; fills their `deflection`.
void predictDeflections(
    const Planner& planner, std::vector<TrajectoryReport>& paths, const DeflectionOptions& options = {});

} // namespace voxhap::planning
