// SPDX-License-Identifier: Apache-2.0
/// @file TestTemplateDevice.cpp
/// @brief The template driver (haptic/devices/drivers/TemplateDevice.h), built by
/// voxhap_add_device_driver: a registered kind is made by name, and the
/// driver turns poses and forces between its frame and LPS.

#include "haptic/devices/DeviceSpec.h"
#include "haptic/devices/drivers/TemplateDevice.h"
#include "haptic/scene/Scene.h"

#include "core/Errors.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {
namespace {

/// Positions are sums of a few products of doubles of order 10² mm.
constexpr double kTemplateTipMm = 1e-9;
/// A 90° turn in doubles: cos(π/2) is 6e-17, times components up to 3.
constexpr double kTurnRoundOff = 1e-15;

bool knownDevice(const std::string& text)
{
    try {
        parseDeviceSpec(text);
        return true;
    } catch (const ValueError&) {
        return false;
    }
}

TEST(DeviceSpec, ARegisteredKindIsMadeByName)
{
    // The template driver, registered by its explicit call: a still handle at
    // the device's origin; forces go out in the device's frame.
    EXPECT_FALSE(knownDevice("template")); // unknown before it is registered
    registerTemplateDevice();
    EXPECT_TRUE(knownDevice("template"));
    const auto usages = deviceKindUsages();
    EXPECT_NE(std::find(usages.begin(), usages.end(), "template"), usages.end());
    const SceneInstance senac(loadScene("senac-average"), nullptr, volume::TissueTable::builtin());
    auto model = senac.makeModel();
    auto device = makeDevice(parseDeviceSpec("template"), deviceContext(*model, 1.0, 5.0, std::nullopt));
    EXPECT_EQ(device->name(), "template");
    const DeviceReading r = device->read(0.0);
    EXPECT_TRUE(r.valid);
    EXPECT_NEAR((r.tip - model->path().origin).norm(), 0.0, kTemplateTipMm);
}

TEST(TemplateDevice, TurnsPosesAndForcesBetweenTheDeviceFrameAndLps)
{
    // A device turned 90° about x, 10 mm off the volume's origin: its z axis
    // (the stand-in handle's needle) is LPS −y, R·(0, 0, 1) = (0, −sin, cos);
    // an LPS force (1, 2, 3) N is Rᵀ·f = (1, 3, −2) in its frame.
    TemplateDeviceOptions o;
    o.originMm = Vec3d(10, 0, 0);
    o.axes = Eigen::AngleAxisd(M_PI / 2, Vec3d::UnitX()).toRotationMatrix();
    TemplateDevice d(o, DeviceLimits{});
    const DeviceReading r = d.read(0.0);
    EXPECT_NEAR((r.tip - Vec3d(10, 0, 0)).norm(), 0.0, kTemplateTipMm);
    EXPECT_NEAR((r.direction - Vec3d(0, -1, 0)).norm(), 0.0, kTurnRoundOff);
    d.write(Vec3d(1, 2, 3), 0.0, 0.0);
    EXPECT_NEAR((d.lastDeviceForce() - Vec3d(1, 3, -2)).norm(), 0.0, kTurnRoundOff);
}

} // namespace
} // namespace voxhap::haptic
