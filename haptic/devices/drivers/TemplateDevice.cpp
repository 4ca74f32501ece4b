// SPDX-License-Identifier: Apache-2.0
/// @file TemplateDevice.cpp
/// @brief A driver's shape, with a stand-in for the vendor's SDK (TemplateDevice.h
/// says how to turn it into a real driver).

#include "haptic/devices/drivers/TemplateDevice.h"

#include "core/Errors.h"
#include "haptic/devices/DeviceSpec.h"

// A real driver includes the vendor's headers here, and only here: the
// header above keeps them away from everything that includes it.

namespace voxhap::haptic {

/// The stand-in for the vendor's SDK: a handle at rest at the device's origin,
/// pointing along its z axis. Replace each member by the SDK's call; keep the
/// calls made from read() and write() to those the vendor documents as safe
/// in its servo callback.
struct TemplateDevice::Sdk {
    double position[3]{0, 0, 0}; ///< in the SDK's units and frame
    double zAxis[3]{0, 0, 1};
    double velocity[3]{0, 0, 0};
    double force[3]{0, 0, 0};
    bool connected = true;

    bool open() { return true; } ///< e.g. the SDK's device-open call
    void close() noexcept { }
    bool readHandle() noexcept { return connected; } ///< fills position, zAxis, velocity
    void sendForce(const double f[3]) noexcept
    {
        for (int i = 0; i < 3; ++i) force[i] = f[i];
    }
};

TemplateDevice::TemplateDevice(const TemplateDeviceOptions& options, const DeviceLimits& limits)
    : mSdk(std::make_unique<Sdk>()), mOptions(options), mLimits(limits)
{
    // Everything that may fail happens here, before the servo thread starts.
    if (!mSdk->open()) throw IoError("template device: cannot open the device");
}

TemplateDevice::~TemplateDevice() { mSdk->close(); }

DeviceReading TemplateDevice::read(double) noexcept
{
    DeviceReading r;
    if (!mSdk->readHandle()) {
        r.lost = true; // the link is gone: the force goes to zero at once
        return r;
    }
    const auto lps = [this](const double v[3]) { return Vec3d(mOptions.axes * Vec3d(v[0], v[1], v[2])); };
    r.tip = mOptions.originMm + lps(mSdk->position) * mOptions.unitsToMm;
    r.direction = lps(mSdk->zAxis).normalized();
    r.velocity = lps(mSdk->velocity) * mOptions.unitsToMm;
    r.valid = true;
    return r;
}

void TemplateDevice::write(const Vec3d& forceN, double, double) noexcept
{
    // LPS newtons to the device's frame (axes is a rotation: its inverse is its transpose).
    mLastDeviceForce = mOptions.axes.transpose() * forceN;
    const double f[3]{mLastDeviceForce.x(), mLastDeviceForce.y(), mLastDeviceForce.z()};
    mSdk->sendForce(f);
}

void registerTemplateDevice()
{
    registerDeviceKind({"template", "template", nullptr, [](const DeviceSpec&, const DeviceContext& c) {
                            TemplateDeviceOptions o;
                            o.originMm = c.path.origin; // a real driver reads its calibration here
                            return std::unique_ptr<Device>(std::make_unique<TemplateDevice>(o, c.limits));
                        }});
}

} // namespace voxhap::haptic
