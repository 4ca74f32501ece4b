// SPDX-License-Identifier: Apache-2.0
/// @file ReplayDevice.h
/// @brief A recorded session played back as a device (architecture.md
/// "Devices"): `voxhap serve --device replay:session.csv`.
#pragma once

#include "haptic/servo/Device.h"
#include "haptic/servo/ServoLoop.h"

#include <vector>

namespace voxhap::haptic {

/// @brief Plays a recorded session's poses and rolls in time (linear between
/// records); readSessionPoses (haptic/servo/Session.h) reads them from a session.csv.
class ReplayDevice final : public Device {
public:
    /// @throw ValueError with fewer than two records
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

} // namespace voxhap::haptic
