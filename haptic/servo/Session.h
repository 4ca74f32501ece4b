// SPDX-License-Identifier: Apache-2.0
/// @file Session.h
/// @brief A recorded servo session (pose, force, plunger, events), its file, its
/// replay device, and the trainee metrics of [S19] (physics.md §2.3).
#pragma once

#include "haptic/servo/Device.h"
#include "haptic/servo/ServoLoop.h"
#include "core/AtomicFile.h"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::haptic {

struct Session {
    std::vector<ServoRecord> records;
    std::vector<Event> events;
};

/// @brief session.csv: t_s, tip_x/y/z_mm, dir_x/y/z, fx/fy/fz_N, plunger_N, depth_mm,
/// axial_N, layer, state, fault, critical, plunger_fraction; then events.csv: t_s, depth_mm, event,
/// layer. Both written and flushed before either replaces an earlier session (OutputSet).
void writeSession(const Session& s, const std::vector<Layer>& layers, const std::filesystem::path& dir);

/// @brief writeSession()'s two files added to @p out, for a caller that writes
/// more outputs of the same run (serve's metrics.json) in one OutputSet.
/// @p s and @p layers are read when @p out commits: they must outlive it.
void addSessionOutputs(
    OutputSet& out, const Session& s, const std::vector<Layer>& layers, const std::filesystem::path& dir);

/// @brief Read the pose columns of a session.csv back (columns after dir_z are ignored).
/// @throw IoError when the file cannot be opened; ValueError, one line naming the
///        file and the line, for a first line that is not the session header, a
///        line whose first seven fields are not finite numbers, a t_s that does
///        not increase, and a file of fewer than two records
std::vector<ServoRecord> readSessionPoses(const std::filesystem::path& file);

/// @brief Plays a recorded session's poses in time (linear between records).
class ReplayDevice final : public Device {
public:
    ReplayDevice(std::vector<ServoRecord> poses, const DeviceLimits& limits);
    DeviceReading read(double timeS) noexcept override;
    void write(const Vec3d&, double, double) noexcept override { }
    const DeviceLimits& limits() const noexcept override { return mLimits; }
    std::string name() const override { return "replay"; }
    bool finished() const noexcept override { return mFinished; }

private:
    std::vector<ServoRecord> mPoses;
    DeviceLimits mLimits;
    std::size_t mIndex = 0;
    bool mFinished = false;
};

/// @brief Trainee metrics after [S19] (physics.md §2.3).
struct TraineeMetrics {
    bool success = true; ///< the dura was not punctured
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

TraineeMetrics traineeMetrics(const Session& s, const std::vector<Layer>& layers, const Vec3d& pathDirection);

} // namespace voxhap::haptic
