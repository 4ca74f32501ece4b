// SPDX-License-Identifier: Apache-2.0
/// @file TestDevices.cpp
/// @brief Devices by name (haptic/devices/DeviceSpec.h): the built-in kinds
/// made for a scene's model behave as their closed forms say, a registered
/// kind is made by name, and bad names are refused in one line before anything
/// is built (a registered kind: TestTemplateDevice.cpp).

#include "common/TempDirTest.h"

#include "core/Errors.h"
#include "haptic/devices/DeviceSpec.h"
#include "haptic/scene/Scene.h"
#include "haptic/servo/ServoLoop.h"
#include "haptic/servo/Session.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

namespace voxhap::haptic {
namespace {

/// Positions are sums of a few products of doubles of order 10² mm.
constexpr double kPositionMm = 1e-9;

const SceneInstance& deviceScene()
{
    static const SceneInstance inst(loadScene("senac-average"), nullptr, volume::TissueTable::builtin());
    return inst;
}

std::string deviceRefusal(const std::string& text)
{
    try {
        parseDeviceSpec(text);
        return "";
    } catch (const ValueError& e) {
        return e.what();
    }
}

TEST(DeviceSpec, UnknownNamesAndBadArgumentsAreRefusedInOneLine)
{
    const std::string bogus = deviceRefusal("bogus");
    EXPECT_EQ(bogus, "device 'bogus' is not hand, sim or replay:FILE"); // the built-in kinds: none registered here
    EXPECT_NE(deviceRefusal("hand:3").find("takes no argument"), std::string::npos);
    EXPECT_NE(deviceRefusal("replay").find("needs a session.csv"), std::string::npos);
    EXPECT_EQ(deviceRefusal("hand"), "");
    EXPECT_EQ(deviceRefusal("sim"), "");
    for (const char* text : {"bogus", "hand:3", "replay"}) EXPECT_EQ(deviceRefusal(text).find('\n'), std::string::npos);
}

TEST(DeviceSpec, TheScriptedDeviceFollowsTheScenesInsertion)
{
    // "sim": from −approach at the scene's speed (or the caller's) to its depth:
    // depth(t) = −approach + v·t until the depth is reached, along the path.
    auto model = deviceScene().makeModel();
    const Scene& scene = deviceScene().scene();
    const double speed = 20.0;
    const DeviceContext c = deviceContext(*model, speed, scene.approachMm, 30.0);
    auto device = makeDevice(parseDeviceSpec("sim"), c);
    EXPECT_EQ(device->name(), "sim-script");
    for (double t : {0.0, 0.1, 0.5, 1.0}) {
        const DeviceReading r = device->read(t);
        const double depth = std::min(-scene.approachMm + speed * t, 30.0);
        EXPECT_TRUE(r.valid);
        EXPECT_NEAR((r.tip - (model->path().origin + depth * model->path().direction)).norm(), 0.0, kPositionMm) << t;
    }
    EXPECT_EQ(device->limits().maxForceN, model->device().maxForceN);
}

TEST(DeviceSpec, TheHandIsMadeCarefulOrReckless)
{
    // The same hand through the servo loop: careful stops in the epidural space
    // (35.4–41.4 mm on senac-average's path), reckless punctures the dura.
    for (const bool careful : {true, false}) {
        auto model = deviceScene().makeModel();
        DeviceContext c = deviceContext(*model, careful ? 1.0 : 10.0, deviceScene().scene().approachMm, std::nullopt);
        c.careful = careful;
        auto device = makeDevice(parseDeviceSpec("hand"), c);
        EXPECT_EQ(device->name(), "sim-hand");
        ServoLoop loop(*model, *device);
        loop.runTicks(careful ? 60000 : 15000);
        bool dura = false, lor = false;
        Event e;
        while (loop.popEvent(e)) {
            dura = dura || e.type == EventType::DuraPuncture;
            lor = lor || e.type == EventType::LossOfResistance;
        }
        EXPECT_TRUE(lor) << careful;
        EXPECT_EQ(dura, !careful);
    }
}

class ReplayByName : public test::TempDirTest { };

TEST_F(ReplayByName, ReplaysTheRecordedPosesAndRefusesABadFileBeforeAnythingIsMade)
{
    // Record a scripted insertion, write it as session.csv, replay it by name:
    // the replayed tips are the recorded ones at the recorded times.
    auto model = deviceScene().makeModel();
    auto script = makeDevice(parseDeviceSpec("sim"), deviceContext(*model, 20.0, 5.0, 20.0));
    ServoLoop loop(*model, *script);
    loop.runTicks(500);
    Session s;
    ServoRecord r;
    while (loop.popRecord(r)) s.records.push_back(r);
    writeSession(s, model->layers(), mDir);
    const DeviceSpec spec = parseDeviceSpec("replay:" + (mDir / "session.csv").string());
    auto replay = makeDevice(spec, deviceContext(*model, 1.0, 5.0, std::nullopt));
    EXPECT_EQ(replay->name(), "replay");
    for (std::size_t i : {std::size_t(0), std::size_t(100), std::size_t(499)}) {
        const ServoRecord& rec = s.records[i];
        // session.csv prints 10 significant digits: 1e-7 mm on tips of order 100 mm.
        EXPECT_NEAR((replay->read(rec.timeS - s.records.front().timeS).tip - rec.tip).norm(), 0.0, 1e-6) << i;
    }
    std::ofstream(mDir / "bad.csv") << "not a session\n";
    EXPECT_THROW(parseDeviceSpec("replay:" + (mDir / "bad.csv").string()), IoError);
    EXPECT_THROW(parseDeviceSpec("replay:" + (mDir / "none.csv").string()), IoError);
}

} // namespace
} // namespace voxhap::haptic
