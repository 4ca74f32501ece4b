// SPDX-License-Identifier: Apache-2.0
/// @file TraineeMetrics.cpp
/// @brief The metrics' catalogue, and the accumulator that computes them.
#include "haptic/servo/TraineeMetrics.h"

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

namespace {

std::optional<double> flag(bool b) { return b ? 1.0 : 0.0; }

} // namespace

const std::vector<TraineeMetricInfo>& traineeMetricCatalogue()
{
    using M = const TraineeMetrics&;
    static const std::vector<TraineeMetricInfo> c{
        {"success", "true/false", "the procedure's goal, by the scene's success rule, without a critical breach",
            MetricKind::Flag, [](M m) { return flag(m.success); }},
        {"success_dura_intact", "true/false", "the dura was not punctured", MetricKind::Flag,
            [](M m) { return flag(m.duraIntact); }},
        {"bone_contacts", "", "times the tip met bone", MetricKind::Count,
            [](M m) { return std::optional<double>(m.boneContacts); }},
        {"pops", "", "punctures felt (skin, ligaments, dura)", MetricKind::Count,
            [](M m) { return std::optional<double>(m.pops); }},
        {"insertion_angle_deg", "deg", "needle against the planned path at skin entry", MetricKind::Number,
            [](M m) { return m.insertionAngleDeg; }},
        {"speed_mean_mm_per_s", "mm/s", "mean advancing speed inside the body", MetricKind::Number,
            [](M m) { return std::optional<double>(m.speedMeanMmPerS); }},
        {"speed_variance_mm2_per_s2", "mm²/s²", "variance of the advancing speed", MetricKind::Number,
            [](M m) { return std::optional<double>(m.speedVarianceMm2PerS2); }},
        {"epidural_overshoot_mm", "mm", "distance travelled inside the epidural space", MetricKind::Number,
            [](M m) { return m.overshootMm; }},
        {"syrrate_per_m", "1/m", "syringe emptied per metre travelled after the derma's puncture", MetricKind::Number,
            [](M m) { return m.syrrate; }},
        {"duration_s", "s", "session length", MetricKind::Number,
            [](M m) { return std::optional<double>(m.durationS); }},
        {"pose_faults", "", "records no hand produces (a non-finite tip, beyond the workspace, faster than a hand)",
            MetricKind::Count, [](M m) { return std::optional<double>(double(m.poseFaults)); }},
        {"force_limited", "", "times the device's peak or I²t limit started cutting the force (physics.md §6.3)",
            MetricKind::Count, [](M m) { return std::optional<double>(m.forceLimits); }},
        {"target_distance_mm", "mm", "closest approach of the tip to the scene's target", MetricKind::Number,
            [](M m) { return m.outcome.targetDistanceMm; }},
        {"csf_reached", "true/false", "the tip reached the CSF", MetricKind::Flag,
            [](M m) { return flag(m.outcome.csfReached); }},
        {"critical_breach", "true/false", "the tip touched a critical structure", MetricKind::Flag,
            [](M m) { return flag(m.outcome.criticalBreach); }},
    };
    return c;
}

const TraineeMetricInfo* findTraineeMetric(std::string_view key)
{
    for (const TraineeMetricInfo& m : traineeMetricCatalogue()) {
        if (m.key == key) return &m;
    }
    return nullptr;
}

TraineeMetricsAccumulator::TraineeMetricsAccumulator(const std::vector<Layer>& layers, const Vec3d& pathDirection,
    const SuccessCriteria& success, std::optional<Vec3d> target)
    : mLayers(layers), mDirection(pathDirection.normalized()), mOutcome(success, layers, target), mSkinT(kNoLimit)
{
}

void TraineeMetricsAccumulator::addEvent(const Event& e) noexcept
{
    mOutcome.addEvent(e);
    if (e.type == EventType::DuraPuncture) mM.duraIntact = false;
    if (e.type == EventType::ForceLimited) ++mM.forceLimits;
    if (e.type == EventType::BoneContact) ++mM.boneContacts;
    if (e.type == EventType::Pop) ++mM.pops;
    if (e.type == EventType::SkinEntry && !std::isfinite(mSkinT)) mSkinT = e.timeS, mSkinDepth = e.depthMm;
}

void TraineeMetricsAccumulator::addRecord(const ServoRecord& r) noexcept
{
    if (!mHaveFirst) mFirst = r, mHaveFirst = true;
    mLast = r;
    // syrrate's starting fraction: the first record from the skin's puncture on.
    if (!mHaveStartFraction && r.timeS >= mSkinT) {
        mStartFraction = std::isfinite(r.plungerFraction) ? r.plungerFraction : 0.0;
        mHaveStartFraction = true;
    }
    // A record is a fault when no hand on the device could have produced it: a
    // non-finite tip, one beyond the workspace's reach of the first tip, or a
    // jump faster than a hand from the last good record. The figures skip it,
    // comparing the next good record with the last good one.
    bool good = r.tip.allFinite() && std::isfinite(r.depthMm) && std::isfinite(r.timeS) &&
        (r.tip - mFirst.tip).norm() <= kWorkspaceReachMm;
    if (good && mHavePrev) {
        const double dt = r.timeS - mPrevGood.timeS;
        if (dt > 0.0 && (r.tip - mPrevGood.tip).norm() / dt > kMaxHandSpeedMmPerS) good = false;
    }
    if (!good) {
        ++mM.poseFaults;
        return;
    }
    mOutcome.addTip(r.tip, r.layer);
    if (!mHavePrev) {
        mPrevGood = r;
        mHavePrev = true;
        return;
    }
    const ServoRecord& a = mPrevGood;
    const ServoRecord& b = r;
    if (!mM.insertionAngleDeg && b.timeS >= mSkinT) {
        mM.insertionAngleDeg = std::acos(std::clamp(b.direction.normalized().dot(mDirection), -1.0, 1.0)) * 180.0 / kPi;
    }
    const double dt = b.timeS - a.timeS;
    const double v = dt > 0.0 ? (b.depthMm - a.depthMm) / dt : 0.0;
    if (b.timeS >= mSkinT && v > 0.0) mSum += v, mSum2 += v * v, ++mN;
    const bool epi =
        b.layer >= 0 && b.layer < int(mLayers.size()) && mLayers[std::size_t(b.layer)].role == LayerRole::Epidural;
    if (epi) mEpidural += std::abs(b.depthMm - a.depthMm), mInEpidural = true;
    mPrevGood = r;
}

TraineeMetrics TraineeMetricsAccumulator::result() const
{
    TraineeMetrics m = mM;
    m.outcome = mOutcome.result();
    m.success = m.outcome.success;
    if (mInEpidural) m.overshootMm = mEpidural;
    if (mN > 0) {
        m.speedMeanMmPerS = mSum / double(mN);
        m.speedVarianceMm2PerS2 = std::max(0.0, mSum2 / double(mN) - m.speedMeanMmPerS * m.speedMeanMmPerS);
    }
    if (mHaveFirst) m.durationS = mLast.timeS - mFirst.timeS;
    // syrrate ([S19], §2.3): syringe fraction emptied from the derma's puncture to the
    // end, per metre travelled along the path in that time.
    if (std::isfinite(mSkinT) && mHaveFirst && std::isfinite(mLast.plungerFraction)) {
        const double travelM = (mLast.depthMm - mSkinDepth) * 1e-3;
        if (travelM > 0.0) m.syrrate = (mLast.plungerFraction - (mHaveStartFraction ? mStartFraction : 0.0)) / travelM;
    }
    return m;
}

} // namespace voxhap::haptic
