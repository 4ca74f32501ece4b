// SPDX-License-Identifier: Apache-2.0
/// @file RiskScore.h
/// @brief One number to rank paths by; lower is safer. The formula:
///
///     R = 100·B + 100·S + 10·N_bone + 10·O                   hard terms
///       + Σ_c max(0, 1 − c_c / m)                            proximity, per critical structure
///       + ℓ / ℓ_needle + F_peak / F_device                   length and force, each ≤ 1 when not flagged
///
/// B = 1 if the path enters a critical structure (clearance ≤ 0), S = 1 if it is
/// longer than the needle, N_bone the bone entries before the target that are
/// not the target's own bone, O = 1 if the predicted peak exceeds the device's
/// peak force; c_c the clearance to structure c, m the planning margin
/// (PlanOptions::marginMm), ℓ the path length, F the predicted peak force.
/// Each soft term is at most 1, so with fewer than 8 critical structures the
/// soft sum stays under 10 and every flagged path ranks below every clean one;
/// among clean paths, nearness to structures, length and force trade one for one
/// at the scale of the margin, the needle and the device.
#pragma once

#include "planning/Trajectory.h"

namespace voxhap::planning {

/// @brief Fill report.risk from the report's fields. @p needleMm, @p deviceMaxN, @p marginMm > 0.
/// @p deviceMaxN is the device's peak in the model's terms: divided by the scene's
/// force_scale, which the device's force is the model's times.
RiskTerms riskScore(const TrajectoryReport& report, double needleMm, double deviceMaxN, double marginMm);

} // namespace voxhap::planning
