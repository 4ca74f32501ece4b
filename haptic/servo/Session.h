// SPDX-License-Identifier: Apache-2.0
/// @file Session.h
/// @brief A recorded servo session (pose, force, plunger, events), its file, and
/// its trainee metrics (TraineeMetrics.h says what they are); haptic/devices/ReplayDevice.h
/// plays one back.
#pragma once

#include "core/AtomicFile.h"
#include "haptic/Procedure.h"
#include "haptic/servo/Device.h"
#include "haptic/servo/ServoLoop.h"
#include "haptic/servo/TraineeMetrics.h"

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::haptic {

struct Session {
    std::vector<ServoRecord> records;
    std::vector<Event> events;
};

/// @brief session.csv: t_s, tip_x/y/z_mm, dir_x/y/z, fx/fy/fz_N, plunger_N, depth_mm,
/// axial_N, layer, state, fault, critical, plunger_fraction, roll_deg (the device's roll, nan when it
/// senses none); then events.csv: t_s, depth_mm, event,
/// layer. Both written and flushed before either replaces an earlier session (OutputSet).
void writeSession(const Session& s, const std::vector<Layer>& layers, const std::filesystem::path& dir);

/// @brief writeSession()'s two files added to @p out, for a caller that writes
/// more outputs of the same run (serve's metrics.json) in one OutputSet.
/// @p s and @p layers are read when @p out commits: they must outlive it.
void addSessionOutputs(
    OutputSet& out, const Session& s, const std::vector<Layer>& layers, const std::filesystem::path& dir);

/// @brief Read the pose columns of a session.csv back, and the roll where the file has a
/// roll_deg column (NaN otherwise, and for nan); the other columns are ignored.
/// @throw IoError when the file cannot be opened; ValueError, one line naming the
///        file and the line, for a first line that is not the session header, a
///        line whose first seven fields are not finite numbers, a roll_deg that is
///        neither a finite number nor nan, a t_s that does not increase, and a file
///        of fewer than two records
std::vector<ServoRecord> readSessionPoses(const std::filesystem::path& file);

TraineeMetrics traineeMetrics(const Session& s, const std::vector<Layer>& layers, const Vec3d& pathDirection,
    const SuccessCriteria& success = {}, std::optional<Vec3d> target = std::nullopt);

class ServoLoop;

/// @brief A session written while it runs: records and
/// events go to session.csv and events.csv as they are drained from the servo
/// loop, and into the trainee metrics, so memory stays bounded at any rate and
/// length. The files grow under temporary names and replace an earlier
/// session only at finish(), together with the caller's other outputs.
/// session.csv ends with a comment line stating how many records were written
/// and how many the servo loop dropped (its record queue was full).
class SessionRecorder {
public:
    /// @p layers must outlive the recorder; @p success and @p target judge the outcome
    /// (TraineeMetricsAccumulator). @throw IoError when a file cannot be created
    SessionRecorder(const std::filesystem::path& dir, const std::vector<Layer>& layers, const Vec3d& pathDirection,
        const SuccessCriteria& success = {}, std::optional<Vec3d> target = std::nullopt);
    ~SessionRecorder();
    SessionRecorder(const SessionRecorder&) = delete;
    SessionRecorder& operator=(const SessionRecorder&) = delete;

    /// @brief Everything the loop has queued: records first, then events, so
    /// that the event of every record taken is at hand (the loop queues a
    /// tick's events before its record).
    void drain(ServoLoop& loop);
    /// @brief An event; applied to the metrics before the first record at or after its time.
    void addEvent(const Event& e);
    void addRecord(const ServoRecord& r);

    long recordCount() const noexcept { return mRecords; }
    long eventCount() const noexcept { return mEvents; }
    /// @brief The last record (for a live view); null before the first.
    const ServoRecord* lastRecord() const noexcept { return mRecords > 0 ? &mLast : nullptr; }
    /// @brief The metrics of everything added so far (pending events included).
    TraineeMetrics metrics();

    /// @brief Write the pending events and session.csv's closing line with
    /// @p droppedRecords, and hand both files to @p out (which puts them in
    /// place at its commit; this recorder must outlive the commit).
    void finish(OutputSet& out, long droppedRecords);

private:
    void writeEvent(const Event& e);
    void applyEventsUpTo(double timeS);

    const std::vector<Layer>& mLayers;
    TraineeMetricsAccumulator mMetrics;
    std::unique_ptr<StreamingOutput> mSession, mEventFile;
    /// Events taken from the loop ahead of their records, oldest first; bounded by
    /// the loop's event queue (what one drain can take).
    std::vector<Event> mPending;
    std::size_t mPendingHead = 0;
    long mRecords = 0, mEvents = 0;
    ServoRecord mLast;
};

} // namespace voxhap::haptic
