// SPDX-License-Identifier: Apache-2.0
/// @file Device.h
/// @brief A haptic device as the servo loop sees it (architecture.md "Devices"):
/// read the needle pose and velocity, write a force, report limits. Simulated,
/// replay and network devices implement it; a vendor SDK plugs in the same way.
#pragma once

#include "core/Math.h"
#include "haptic/DeviceLimits.h"
#include "haptic/Events.h"

#include <limits>
#include <string>

namespace voxhap::haptic {

/// @brief One reading. @c valid is false when the device has nothing new (a quiet
/// network stream): the servo loop's watchdog counts those.
struct DeviceReading {
    Vec3d tip{0, 0, 0};       ///< [mm, LPS]
    Vec3d direction{0, 0, 1}; ///< hub to tip, unit
    Vec3d velocity{0, 0, 0};  ///< [mm/s]
    bool valid = false;
    bool lost = false; ///< the link is gone: the force must be zero at once
    /// How long ago the pose was measured [s]: 0 for devices read in the tick; a
    /// network client's last pose ages between messages. The watchdog counts a
    /// valid but aging pose as quiet time, so a client that stops sending has its
    /// force ramped down 20 ms after its last pose, not 20 ms after the pose
    /// stopped being valid.
    double poseAgeS = 0.0;
    /// Fraction of the loss-of-resistance syringe emptied, 0..1, for devices with a
    /// plunger channel ([S19]'s pneumatic syringe); NaN otherwise.
    double plungerFraction = std::numeric_limits<double>::quiet_NaN();
    /// The needle's roll about its axis [rad], for devices that sense it; NaN
    /// otherwise (a bending needle's bevel then keeps the scene's orientation,
    /// physics.md §9.3).
    double rollRad = std::numeric_limits<double>::quiet_NaN();
};

class Device {
public:
    virtual ~Device() = default;
    /// @brief The pose at servo time @p timeS. Called from the servo thread: must not
    /// block, allocate or throw.
    virtual DeviceReading read(double timeS) noexcept = 0;
    /// @brief The force to render until the next tick [N], and the syringe plunger's
    /// force [N] for devices that have one. Same rules as read().
    virtual void write(const Vec3d& forceN, double plungerN, double timeS) noexcept = 0;
    /// @brief An insertion event, for devices that show or forward them. Same rules as read().
    virtual void event(const Event&) noexcept { }
    virtual const DeviceLimits& limits() const noexcept = 0;
    virtual std::string name() const = 0;
    /// @brief A scripted or replayed device that has reached its end.
    virtual bool finished() const noexcept { return false; }
};

} // namespace voxhap::haptic
