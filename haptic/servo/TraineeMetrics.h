// SPDX-License-Identifier: Apache-2.0
/// @file TraineeMetrics.h
/// @brief The trainee metrics of a session after [S19] (physics.md §2.3): what
/// each one is called in metrics.json, its unit and meaning, and how it is
/// computed from the servo loop's records and events, in one place.
/// assessment/ judges them (reference ranges and verdicts); it names none.
#pragma once

#include "haptic/Events.h"
#include "haptic/Layer.h"
#include "haptic/Procedure.h"
#include "haptic/servo/ServoLoop.h"

#include <optional>
#include <string_view>
#include <vector>

namespace voxhap::haptic {

/// @brief Trainee metrics after [S19] (physics.md §2.3).
struct TraineeMetrics {
    bool success = true;      ///< under the scene's success rule (Procedure.h)
    bool duraIntact = true;   ///< the dura was not punctured ([S19]'s success, §2.3)
    ProcedureOutcome outcome; ///< the rule, why it succeeded or failed, the closest approach to the target
    int forceLimits = 0;      ///< times the device's peak or I²t limit started cutting the force (§6.3)
    int boneContacts = 0;
    int pops = 0;
    std::optional<double> insertionAngleDeg; ///< needle against the planned path at skin entry
    double speedMeanMmPerS = 0;              ///< along the path, while advancing inside the body
    double speedVarianceMm2PerS2 = 0;
    std::optional<double> overshootMm; ///< distance travelled inside the epidural space
    std::optional<double> syrrate;     ///< fraction emptied per metre [1/m]; null without a plunger channel
    double durationS = 0;
    /// Records no hand on a desk-mounted device produces, left out of every
    /// figure above: a non-finite tip, a tip more than kWorkspaceReachMm from the
    /// session's first one, or a step faster than kMaxHandSpeedMmPerS.
    long poseFaults = 0;
};

/// Farthest a tip may be from the session's first tip [mm]: beyond the largest
/// desk-mounted haptic workspace (Phantom Premium 3.0: 838 × 584 × 406 mm) [chosen].
inline constexpr double kWorkspaceReachMm = 1000.0;
/// Fastest a hand moves a needle's tip [mm/s]: fast human reaching peaks near
/// 2 m/s; 5 m/s leaves margin [chosen].
inline constexpr double kMaxHandSpeedMmPerS = 5000.0;

/// @brief traineeMetrics() one record and one event at a time, in time order
/// (an event before the record of its tick), with memory that does not grow
/// with the session: what a recorder of an hour-long session keeps.
class TraineeMetricsAccumulator {
public:
    /// @p success and @p target judge the outcome (Procedure.h): by default [S19]'s
    /// dura_intact, without a target.
    TraineeMetricsAccumulator(const std::vector<Layer>& layers, const Vec3d& pathDirection,
        const SuccessCriteria& success = {}, std::optional<Vec3d> target = std::nullopt);
    void addEvent(const Event& e) noexcept;
    void addRecord(const ServoRecord& r) noexcept;
    TraineeMetrics result() const;

private:
    const std::vector<Layer>& mLayers;
    Vec3d mDirection;
    OutcomeTracker mOutcome;
    TraineeMetrics mM;
    double mSkinT, mSkinDepth = 0.0;
    double mSum = 0, mSum2 = 0, mEpidural = 0;
    long mN = 0;
    bool mInEpidural = false;
    bool mHaveFirst = false, mHavePrev = false, mHaveStartFraction = false;
    ServoRecord mFirst, mLast, mPrevGood;
    double mStartFraction = 0.0;
};

/// @brief How a metric's value is written in metrics.json.
enum class MetricKind {
    Flag,   ///< true/false
    Count,  ///< a whole number
    Number, ///< a real number in its unit, or null when the session did not measure it
};

/// @brief One trainee metric: its metrics.json key, unit and meaning, and its
/// value in a session's TraineeMetrics.
struct TraineeMetricInfo {
    std::string_view key;
    std::string_view unit; ///< "" for counts; "true/false" for a flag
    std::string_view description;
    MetricKind kind = MetricKind::Number;
    /// The value: a flag as 1/0; nothing when the session did not measure it.
    std::optional<double> (*value)(const TraineeMetrics&) = nullptr;
};

/// @brief Every metric a session computes, in report order.
const std::vector<TraineeMetricInfo>& traineeMetricCatalogue();
/// @brief The catalogue entry of @p key, or null.
const TraineeMetricInfo* findTraineeMetric(std::string_view key);

} // namespace voxhap::haptic
