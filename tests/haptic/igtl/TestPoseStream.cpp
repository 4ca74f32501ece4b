// SPDX-License-Identifier: Apache-2.0
/// @file TestPoseStream.cpp
/// @brief The live-needle stream over a real loopback socket: a PoseSender's
/// pose reads back exactly (to the float32 the TRANSFORM carries), the sender
/// reconnects by itself to a receiver started later, the receiver survives a
/// garbage header, and addresses are checked with one clear message. A bending
/// needle's shaft rides a POINT message ahead of its pose and belongs to that
/// pose only.

#include "haptic/igtl/PoseStream.h"

#include "core/Errors.h"

#include <igtlPointMessage.h>
#include <igtlTransformMessage.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <thread>
#include <vector>

namespace voxhap::haptic {
namespace {

template <typename Pred> bool waitUntil(Pred&& p, double seconds = 5.0)
{
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
        if (p()) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return p();
}

/// The value a double becomes on the wire: TRANSFORM holds float32.
double wire(double v) { return double(float(v)); }

TEST(PoseStream, SentPoseReadsBackAsItsFloat32Values)
{
    PoseReceiver rx(0);
    ASSERT_GT(rx.port(), 0);
    PoseSender tx("127.0.0.1", rx.port());
    // A direction that is not a float exactly (0.6, 0.8) and a tip that is not either (0.1).
    const StreamedPose sent{Vec3d(12.5, -40.1, 173.25), Vec3d(0.6, 0.0, -0.8)};
    ASSERT_TRUE(waitUntil([&] { return tx.send(sent) && rx.poses() > 0; }));
    const auto got = rx.latest();
    ASSERT_TRUE(got.has_value());
    for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(got->tip[i], wire(sent.tip[i])) << "tip " << i;
        EXPECT_EQ(got->direction[i], wire(sent.direction[i])) << "direction " << i;
    }
    // Every pose sent arrives (TCP on loopback loses none), and a later one replaces the earlier.
    ASSERT_TRUE(waitUntil([&] { return rx.poses() == tx.sent(); }));
    const StreamedPose next{Vec3d(1, 2, 3), Vec3d(0, 1, 0)};
    ASSERT_TRUE(tx.send(next));
    ASSERT_TRUE(waitUntil([&] { return rx.poses() == tx.sent(); }));
    EXPECT_EQ(rx.latest()->tip, Vec3d(1, 2, 3));
    EXPECT_EQ(rx.latest()->direction, Vec3d(0, 1, 0));
}

TEST(PoseStream, SenderConnectsToAViewerThatStartsLater)
{
    // Find a free port, then release it for the receiver to take later.
    int port = 0;
    {
        PoseReceiver probe(0);
        port = probe.port();
    }
    PoseSender tx("127.0.0.1", port, 0.01);
    EXPECT_FALSE(tx.send({Vec3d(1, 1, 1), Vec3d(0, 0, 1)})) << "nobody listening: dropped, not blocked";
    EXPECT_FALSE(tx.connected());
    PoseReceiver rx(port);
    ASSERT_TRUE(waitUntil([&] { return tx.send({Vec3d(1, 1, 1), Vec3d(0, 0, 1)}) && rx.poses() > 0; }));
    EXPECT_EQ(rx.latest()->tip, Vec3d(1, 1, 1));
}

/// Writes @p bytes to a fresh connection to @p port and leaves it open.
int sendRaw(int port, const std::vector<unsigned char>& bytes)
{
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(std::uint16_t(port));
    ::inet_pton(AF_INET, "127.0.0.1", &a.sin_addr);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) return -1;
    if (::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL) != ssize_t(bytes.size())) return -1;
    return fd;
}

TEST(PoseStream, ReceiverDropsAGarbageHeaderAndAcceptsTheNextSender)
{
    PoseReceiver rx(0);
    {
        // Version 0xffff, body size 2^64 − 1.
        const int fd = sendRaw(rx.port(), std::vector<unsigned char>(58, 0xff));
        ASSERT_GE(fd, 0);
        EXPECT_TRUE(waitUntil([&] { return rx.rejected() == 1; }));
        ::close(fd);
    }
    EXPECT_FALSE(rx.latest().has_value());
    PoseSender tx("127.0.0.1", rx.port(), 0.01);
    ASSERT_TRUE(waitUntil([&] { return tx.send({Vec3d(4, 5, 6), Vec3d(1, 0, 0)}) && rx.poses() > 0; }));
    EXPECT_EQ(rx.latest()->tip, Vec3d(4, 5, 6));
}

/// A shaft that is not float32 exactly: 41 points on an arc of radius 300 mm.
std::vector<Vec3d> arcShaft()
{
    std::vector<Vec3d> shaft;
    for (int i = 0; i <= 40; ++i) {
        const double s = 2.0 * i, a = s / 300.0; // 80 mm of arc
        shaft.emplace_back(300.0 * (1.0 - std::cos(a)) + 0.1, -20.0, 100.0 - 300.0 * std::sin(a));
    }
    return shaft;
}

TEST(PoseStream, BentShaftArrivesWithItsPoseAndOnlyWithIt)
{
    PoseReceiver rx(0);
    PoseSender tx("127.0.0.1", rx.port(), 0.01);
    StreamedPose bent{Vec3d(0.1, -20, 20), Vec3d(0, 0, -1), arcShaft()};
    ASSERT_TRUE(waitUntil([&] { return tx.send(bent) && rx.poses() > 0; }));
    ASSERT_TRUE(waitUntil([&] { return rx.poses() == tx.sent(); }));
    auto got = rx.latest();
    ASSERT_EQ(got->shaft.size(), bent.shaft.size());
    for (std::size_t i = 0; i < bent.shaft.size(); ++i) {
        for (int c = 0; c < 3; ++c)
            EXPECT_EQ(got->shaft[i][c], wire(bent.shaft[i][c])) << "point " << i << " axis " << c;
    }
    // The control: a pose sent without a shaft is straight, not drawn with the last one.
    ASSERT_TRUE(tx.send({Vec3d(0, -20, 20), Vec3d(0, 0, -1), {}}));
    ASSERT_TRUE(waitUntil([&] { return rx.poses() == tx.sent(); }));
    EXPECT_TRUE(rx.latest()->shaft.empty());
}

/// A POINT of @p points named @p device, packed by the library, then a TRANSFORM.
std::vector<unsigned char> pointThenPose(const char* device, int points, bool corruptCrc = false)
{
    auto pm = igtl::PointMessage::New();
    pm->SetDeviceName(device);
    for (int i = 0; i < points; ++i) {
        auto e = igtl::PointElement::New();
        e->SetPosition(float(i), 2.0f, 3.0f);
        pm->AddPointElement(e);
    }
    pm->Pack();
    auto tm = igtl::TransformMessage::New();
    tm->SetDeviceName("voxhap-needle");
    igtl::Matrix4x4 m;
    igtl::IdentityMatrix(m);
    tm->SetMatrix(m);
    tm->Pack();
    std::vector<unsigned char> out(static_cast<unsigned char*>(pm->GetPackPointer()),
        static_cast<unsigned char*>(pm->GetPackPointer()) + pm->GetPackSize());
    if (corruptCrc) out[57] ^= 0x01; // the CRC-64's last byte
    out.insert(out.end(), static_cast<unsigned char*>(tm->GetPackPointer()),
        static_cast<unsigned char*>(tm->GetPackPointer()) + tm->GetPackSize());
    return out;
}

TEST(PoseStream, OnlyTheShaftsPointMessageMakesAShaftAndItsCrcIsChecked)
{
    {
        PoseReceiver rx(0);
        const int fd = sendRaw(rx.port(), pointThenPose("voxhap-shaft", 3));
        ASSERT_GE(fd, 0);
        ASSERT_TRUE(waitUntil([&] { return rx.poses() == 1; }));
        ASSERT_EQ(rx.latest()->shaft.size(), 3u) << "the library's POINT, read by voxhap's layout";
        EXPECT_EQ(rx.latest()->shaft[2], Vec3d(2, 2, 3));
        ::close(fd);
    }
    {
        PoseReceiver rx(0); // a POINT of another name (a tracker's fiducials): skipped
        const int fd = sendRaw(rx.port(), pointThenPose("fiducials", 3));
        ASSERT_TRUE(waitUntil([&] { return rx.poses() == 1; }));
        EXPECT_TRUE(rx.latest()->shaft.empty());
        EXPECT_EQ(rx.rejected(), 0);
        ::close(fd);
    }
    {
        PoseReceiver rx(0); // a damaged shaft: refused, the link dropped, its pose never taken
        const int fd = sendRaw(rx.port(), pointThenPose("voxhap-shaft", 3, true));
        ASSERT_TRUE(waitUntil([&] { return rx.rejected() == 1; }));
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
        EXPECT_EQ(rx.poses(), 0);
        ::close(fd);
    }
}

TEST(PoseStream, HostAndPortAreChecked)
{
    std::string host;
    int port = 0;
    parseHostPort("18945", "--viewer", host, port);
    EXPECT_EQ(host, "127.0.0.1");
    EXPECT_EQ(port, 18945);
    parseHostPort("10.0.0.7:2000", "--viewer", host, port);
    EXPECT_EQ(host, "10.0.0.7");
    EXPECT_EQ(port, 2000);
    for (const char* bad : {"", "0", "70000", "abc", "1.2.3.4:", ":80", "localhost:80", "12x"}) {
        try {
            parseHostPort(bad, "--viewer", host, port);
            ADD_FAILURE() << "accepted '" << bad << "'";
        } catch (const ValueError& e) {
            EXPECT_EQ(std::string(e.what()).rfind("--viewer: ", 0), 0u) << e.what();
        }
    }
}

} // namespace
} // namespace voxhap::haptic
