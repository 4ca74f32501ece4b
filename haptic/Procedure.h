// SPDX-License-Identifier: Apache-2.0
/// @file Procedure.h
/// @brief What success is in each procedure, as a scene's
/// "success" block states it, and the outcome of one insertion, followed tick by
/// tick by `voxhap simulate` (runInsertion) and `voxhap serve` (the session's
/// metrics).
///
/// Rules, each with its source:
/// - dura_intact: an epidural succeeds when the dura is not punctured ([S19],
///   physics.md §2.3);
/// - reach_csf: a lumbar puncture or spinal anaesthesia succeeds when the tip
///   enters the CSF, the [LP] table's "puncture aim" (physics.md §4), or
///   punctures the dura where the layers end at it (Conci's table, §3.2);
/// - reach_target: a spine biopsy succeeds when the tip comes within a stated
///   radius of the target ([K01], physics.md §1: the biopsy of a vertebral
///   lesion). The tip is the device's, so a tip pushed into bone against the
///   contact force counts where the hand put it.
/// Every rule also fails on a critical-structure breach (physics.md §1.1: the
/// path must not touch lung, kidney, aorta or cord) [chosen].
#pragma once

#include "core/Math.h"
#include "haptic/Events.h"
#include "haptic/Layer.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::haptic {

enum class SuccessRule : std::uint8_t {
    DuraIntact,  ///< [S19] §2.3: the dura is not punctured
    ReachCsf,    ///< [LP] §4: the tip enters the CSF
    ReachTarget, ///< [K01] §1: the tip within radiusMm of the target
};

/// @brief "dura_intact", "reach_csf", "reach_target". @throw ValueError
SuccessRule parseSuccessRule(const std::string& name);
const char* successRuleName(SuccessRule r);

struct SuccessCriteria {
    SuccessRule rule = SuccessRule::DuraIntact;
    /// reach_target: how close the tip must come to the target [mm]. Default 5 mm
    /// [chosen]: half of a 1 cm lesion; a scene should state its own.
    double radiusMm = 5.0;
};

/// @brief One insertion's outcome under a rule.
struct ProcedureOutcome {
    SuccessRule rule = SuccessRule::DuraIntact;
    bool success = false;
    std::string reason; ///< one line: why it succeeded or failed
    bool duraPunctured = false, csfReached = false, criticalBreach = false;
    std::optional<double> duraPunctureMm, breachMm; ///< depth of the first of each [mm]
    /// Closest approach of the tip to the target [mm]; none without a target.
    std::optional<double> targetDistanceMm;
};

/// @brief Follows one insertion: events and tip positions, in time order.
/// addEvent() and addTip() never allocate or throw.
class OutcomeTracker {
public:
    /// @p layers must outlive the tracker; @p target is the scene's (none: no distance)
    OutcomeTracker(const SuccessCriteria& criteria, const std::vector<Layer>& layers, std::optional<Vec3d> target);
    void addEvent(const Event& e) noexcept;
    /// @brief The tip at one tick, with the index of the layer it is in (-1 outside).
    void addTip(const Vec3d& tip, int layer) noexcept;
    ProcedureOutcome result() const;
    const SuccessCriteria& criteria() const noexcept { return mCriteria; }

private:
    SuccessCriteria mCriteria;
    const std::vector<Layer>* mLayers;
    std::optional<Vec3d> mTarget;
    double mClosest2 = -1.0; ///< squared closest distance [mm²]; < 0 before the first tip
    double mDuraMm = 0.0, mBreachMm = 0.0;
    bool mDura = false, mCsf = false, mBreach = false;
};

} // namespace voxhap::haptic
