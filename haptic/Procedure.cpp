// SPDX-License-Identifier: Apache-2.0
/// @file Procedure.cpp
/// @brief Success rules per procedure (physics.md §1, §1.1, §2.3, §4).

#include "haptic/Procedure.h"

#include "core/Errors.h"
#include "core/Format.h"

#include <cmath>

namespace voxhap::haptic {

SuccessRule parseSuccessRule(const std::string& name)
{
    if (name == "dura_intact") return SuccessRule::DuraIntact;
    if (name == "reach_csf") return SuccessRule::ReachCsf;
    if (name == "reach_target") return SuccessRule::ReachTarget;
    throw ValueError("unknown success rule '" + name + "' (dura_intact, reach_csf, reach_target)");
}

const char* successRuleName(SuccessRule r)
{
    switch (r) {
    case SuccessRule::DuraIntact:
        return "dura_intact";
    case SuccessRule::ReachCsf:
        return "reach_csf";
    case SuccessRule::ReachTarget:
        return "reach_target";
    }
    return "?";
}

OutcomeTracker::OutcomeTracker(
    const SuccessCriteria& criteria, const std::vector<Layer>& layers, std::optional<Vec3d> target)
    : mCriteria(criteria), mLayers(&layers), mTarget(target)
{
}

void OutcomeTracker::addEvent(const Event& e) noexcept
{
    if (e.type == EventType::DuraPuncture && !mDura) mDura = true, mDuraMm = e.depthMm;
    if (e.type == EventType::CriticalBreach && !mBreach) mBreach = true, mBreachMm = e.depthMm;
}

void OutcomeTracker::addTip(const Vec3d& tip, int layer) noexcept
{
    if (layer >= 0 && std::size_t(layer) < mLayers->size() && (*mLayers)[std::size_t(layer)].role == LayerRole::Csf)
        mCsf = true;
    if (!mTarget || !tip.allFinite()) return;
    const double d2 = (tip - *mTarget).squaredNorm();
    if (mClosest2 < 0.0 || d2 < mClosest2) mClosest2 = d2;
}

ProcedureOutcome OutcomeTracker::result() const
{
    ProcedureOutcome o;
    o.rule = mCriteria.rule;
    o.duraPunctured = mDura;
    o.csfReached = mCsf;
    o.criticalBreach = mBreach;
    if (mDura) o.duraPunctureMm = mDuraMm;
    if (mBreach) o.breachMm = mBreachMm;
    if (mClosest2 >= 0.0) o.targetDistanceMm = std::sqrt(mClosest2);
    switch (mCriteria.rule) {
    case SuccessRule::DuraIntact:
        o.success = !mDura;
        o.reason = mDura ? "dura punctured at " + fixed(mDuraMm) + " mm" : "dura intact";
        break;
    case SuccessRule::ReachCsf:
        // A table without a CSF row (Conci's merged epidural/dura, §3.2) ends at the
        // dura: its puncture is the CSF reached.
        o.success = mCsf || mDura;
        o.reason = mCsf ? "the tip reached the CSF"
            : mDura     ? "dura punctured at " + fixed(mDuraMm) + " mm: the CSF reached"
                        : "the tip never reached the CSF";
        break;
    case SuccessRule::ReachTarget: {
        const std::string radius = "the " + fixed(mCriteria.radiusMm) + " mm radius";
        if (!o.targetDistanceMm) {
            o.success = false;
            o.reason = "no target to reach";
        } else {
            o.success = *o.targetDistanceMm <= mCriteria.radiusMm;
            o.reason = "closest approach " + fixed(*o.targetDistanceMm) + " mm to the target, " +
                (o.success ? "within " : "outside ") + radius;
        }
        break;
    }
    }
    if (mBreach) {
        o.success = false;
        o.reason += "; critical breach at " + fixed(mBreachMm) + " mm";
    }
    return o;
}

} // namespace voxhap::haptic
