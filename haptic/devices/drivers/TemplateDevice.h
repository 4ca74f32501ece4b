// SPDX-License-Identifier: Apache-2.0
/// @file TemplateDevice.h
/// @brief The starting point of a driver for a vendor's haptic device
/// (architecture.md "Devices"): copy this file and TemplateDevice.cpp to
/// haptic/devices/drivers/<Vendor>Device.h/.cpp, replace the SDK stand-in in the .cpp
/// by the vendor's calls, and build it with voxhap_add_device_driver()
/// (cmake/VoxhapDeviceDriver.cmake), which finds the SDK at configure time.
///
/// The contract of haptic::Device (haptic/servo/Device.h), as a driver meets it:
/// - **Threads.** read(), write() and event() are called from the servo thread
///   only, once per tick (1 kHz by default), in that order: read, step the
///   model, write. They must not block, allocate, lock a mutex, throw, log or
///   touch the file system: each returns in microseconds. Everything that can
///   fail (opening the device, calibration, allocating buffers) happens in the
///   constructor, which may throw.
/// - **Units and frame.** Positions in millimetres and velocities in mm/s, in
///   the volume's patient LPS frame: the driver owns the transform from the
///   device's frame (its workspace, its units) to LPS, set at construction.
///   `direction` is the needle's axis from hub to tip, unit length. Forces
///   written are in newtons, in LPS; the driver turns them into the device's
///   frame and units.
/// - **Readings.** `valid` is false when the device has nothing new this tick
///   (the servo loop's watchdog counts those and ramps the force down after
///   20 ms); `lost` is true when the link is gone, and the force goes to zero
///   at once. `poseAgeS` is how old the pose is when the SDK says so.
///   `plungerFraction` stays NaN unless the device has a syringe plunger.
///   A field added to DeviceReading later has a default that means "the
///   device does not measure it": a driver that does not set it stays correct.
/// - **Limits.** limits() describes what the device can render (peak and
///   continuous force, stable stiffness; haptic/DeviceLimits.h): the safety
///   stage keeps the force within them, so they must be the device's real ones.
/// - **Ending.** finished() is true when a scripted or replayed device has
///   nothing more to play; a hardware device returns false.
/// - **Registration.** registerTemplateDevice() makes the kind known by name
///   ("template"), so that `voxhap serve --device template`, Python's
///   `voxhap.make_device("template", ...)` and embedding programs can build
///   it. Call it once at start-up: a static initialiser would be dropped by
///   the linker from a static library.
#pragma once

#include "haptic/servo/Device.h"

#include <memory>

namespace voxhap::haptic {

/// @brief What the driver needs at construction besides the device's limits.
struct TemplateDeviceOptions {
    /// Where the device's origin lies in the volume [mm, LPS], and the
    /// device's axes as LPS columns: the frame transform the driver owns.
    Vec3d originMm{0, 0, 0};
    Mat3d axes = Mat3d::Identity();
    double unitsToMm = 1.0; ///< the SDK's length unit in mm (metres: 1000)
};

class TemplateDevice final : public Device {
public:
    /// @brief Open the device. @throw IoError when it cannot be opened
    TemplateDevice(const TemplateDeviceOptions& options, const DeviceLimits& limits);
    ~TemplateDevice() override;
    TemplateDevice(const TemplateDevice&) = delete;
    TemplateDevice& operator=(const TemplateDevice&) = delete;

    DeviceReading read(double timeS) noexcept override;
    void write(const Vec3d& forceN, double plungerN, double timeS) noexcept override;
    const DeviceLimits& limits() const noexcept override { return mLimits; }
    std::string name() const override { return "template"; }

    /// @brief The last force sent to the device, in its own frame and units
    /// (for tests of the frame transform).
    const Vec3d& lastDeviceForce() const noexcept { return mLastDeviceForce; }

private:
    struct Sdk; ///< the vendor's handle: only the .cpp knows the SDK's headers
    std::unique_ptr<Sdk> mSdk;
    TemplateDeviceOptions mOptions;
    DeviceLimits mLimits;
    Vec3d mLastDeviceForce{0, 0, 0};
};

/// @brief Make the kind "template" known to parseDeviceSpec() and makeDevice()
/// (DeviceSpec.h). Its argument, if any, is ignored.
void registerTemplateDevice();

} // namespace voxhap::haptic
