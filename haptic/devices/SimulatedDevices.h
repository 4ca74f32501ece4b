// SPDX-License-Identifier: Apache-2.0
/// @file SimulatedDevices.h
/// @brief Devices without hardware, for closed-loop tests and demos
/// (architecture.md "Devices"): a scripted insertion, and a mass-spring "hand"
/// that pushes the needle along the path and reacts to the loss of resistance.
#pragma once

#include "haptic/force/NeedleForceModel.h"
#include "haptic/scene/ScriptedInsertion.h"
#include "haptic/servo/Device.h"

namespace voxhap::haptic {

/// @brief Plays an InsertionScript along a path; ignores the force.
class ScriptedDevice final : public Device {
public:
    ScriptedDevice(const NeedlePath& path, InsertionScript script, const DeviceLimits& limits);
    DeviceReading read(double timeS) noexcept override;
    void write(const Vec3d&, double, double) noexcept override { }
    const DeviceLimits& limits() const noexcept override { return mLimits; }
    std::string name() const override { return "sim-script"; }
    bool finished() const noexcept override { return mFinished; }

private:
    NeedlePath mPath;
    InsertionScript mScript;
    DeviceLimits mLimits;
    bool mFinished = false;
};

/// @brief A trainee's hand (1-D along the path): a mass held by a grip spring and
/// damper to a set point that advances at the chosen speed. A careful hand stops
/// advancing the set point a reaction time after it feels the plunger give way
/// (loss of resistance); a reckless one does not. [chosen] defaults: a 0.3 kg hand
/// and needle, 1 N/mm grip, 0.035 N·s/mm damping (critical for that mass and grip:
/// 2·sqrt(k·m)), 0.25 s reaction (a simple visual-motor reaction time).
struct HandParams {
    double massKg = 0.3;
    double gripNPerMm = 1.0;
    double dampingNsPerMm = 0.035;
    double speedMmPerS = 2.0; ///< set-point speed
    double startMm = -5.0;    ///< depth where the hand starts
    double maxDepthMm = 80.0; ///< the set point stops here
    bool stopOnLor = true;    ///< careful: stop after feeling the loss of resistance
    double lorDropN = 3.0;    ///< the plunger force below which the hand feels the loss [N]
    double reactionS = 0.25;
    /// The syringe: once the plunger has been felt blocked, the thumb presses it with
    /// this force, and it empties at emptyPerS·(1 − plunger force/thumb force) while
    /// that is positive [chosen: a 5 N thumb empties a free syringe in 5 s].
    double thumbForceN = 5.0;
    double emptyPerS = 0.2;
};

class HandDevice final : public Device {
public:
    HandDevice(const NeedlePath& path, const HandParams& p, const DeviceLimits& limits);
    DeviceReading read(double timeS) noexcept override;
    void write(const Vec3d& forceN, double plungerN, double timeS) noexcept override;
    const DeviceLimits& limits() const noexcept override { return mLimits; }
    std::string name() const override { return "sim-hand"; }
    double depthMm() const noexcept { return mX; }
    double setPointMm() const noexcept { return mSet; }
    bool feltLor() const noexcept { return mFeltAt >= 0.0; }

private:
    NeedlePath mPath;
    HandParams mP;
    DeviceLimits mLimits;
    double mX, mV = 0.0, mSet, mT = 0.0;
    double mPeakPlunger = 0.0, mFeltAt = -1.0, mEmptied = 0.0;
    bool mStopped = false;
};

} // namespace voxhap::haptic
