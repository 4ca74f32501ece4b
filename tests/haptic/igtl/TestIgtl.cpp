// SPDX-License-Identifier: Apache-2.0
/// @file TestIgtl.cpp
/// @brief The OpenIGTLink bridge over a real loopback socket: Debian's example
/// tracker client (built from openigtlink-examples, not written here) drives it;
/// garbage, oversized, corrupted and truncated messages leave it alive; a lost
/// client zeroes the force within one tick.

#include "common/Prerequisites.h"
#include "haptic/igtl/IgtlDevice.h"
#include "haptic/scene/Scene.h"
#include "haptic/servo/ServoLoop.h"

#include <igtlSensorMessage.h>
#include <igtlTransformMessage.h>
#include <igtl_util.h>

#include <arpa/inet.h>
#include <csignal>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Geometry> // for cross and unitOrthogonal
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <functional>
#include <thread>
#include <vector>

namespace voxhap::haptic {
namespace {

IgtlOptions anyPort()
{
    IgtlOptions o;
    o.port = 0;
    return o;
}

template <typename Pred> bool waitFor(Pred&& p, double seconds = 5.0)
{
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
        if (p()) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return p();
}

/// A raw TCP client, so that the test can send what no library would.
class RawClient {
public:
    explicit RawClient(int port)
    {
        mFd = ::socket(AF_INET, SOCK_STREAM, 0);
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_port = htons(std::uint16_t(port));
        ::inet_pton(AF_INET, "127.0.0.1", &a.sin_addr);
        mOk = ::connect(mFd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    }
    ~RawClient() { close(); }
    void close()
    {
        if (mFd >= 0) ::close(mFd);
        mFd = -1;
    }
    bool ok() const { return mOk; }
    void send(const void* p, std::size_t n) { (void)::send(mFd, p, n, MSG_NOSIGNAL); }
    /// A TRANSFORM with the tip at @p tip and the needle (the tool's z axis) along @p dir;
    /// @p corrupt flips a body byte after packing.
    void sendPose(const Vec3d& tip, bool corrupt = false, const Vec3d& dir = Vec3d(0, 0, 1))
    {
        auto msg = igtl::TransformMessage::New();
        msg->SetDeviceName("Needle");
        igtl::Matrix4x4 m;
        igtl::IdentityMatrix(m);
        const Vec3d z = dir.normalized(), x = z.unitOrthogonal(), y = z.cross(x);
        for (int i = 0; i < 3; ++i) m[i][0] = float(x[i]), m[i][1] = float(y[i]), m[i][2] = float(z[i]);
        m[0][3] = float(tip.x()), m[1][3] = float(tip.y()), m[2][3] = float(tip.z());
        msg->SetMatrix(m);
        msg->Pack();
        std::vector<unsigned char> bytes(static_cast<unsigned char*>(msg->GetPackPointer()),
            static_cast<unsigned char*>(msg->GetPackPointer()) + msg->GetPackSize());
        if (corrupt) bytes[70] ^= 0x5a;
        send(bytes.data(), bytes.size());
    }
    /// The next SENSOR reply's three values [N], or false within 2 s.
    bool readForce(double (&f)[3])
    {
        for (;;) {
            unsigned char h[58];
            if (!readExactly(h, 58)) return false;
            auto head = igtl::MessageHeader::New();
            head->InitPack();
            std::memcpy(head->GetPackPointer(), h, 58);
            head->Unpack();
            std::vector<unsigned char> body(std::size_t(head->GetBodySizeToRead()));
            if (!readExactly(body.data(), body.size())) return false;
            if (std::strcmp(head->GetDeviceType(), "SENSOR") != 0) continue; // events (STRING) interleave
            auto s = igtl::SensorMessage::New();
            s->SetMessageHeader(head);
            s->AllocatePack();
            std::memcpy(s->GetPackBodyPointer(), body.data(), body.size());
            if (!(s->Unpack(1) & igtl::MessageHeader::UNPACK_BODY) || s->GetLength() != 3) return false;
            for (unsigned i = 0; i < 3; ++i) f[i] = s->GetValue(i);
            return true;
        }
    }

private:
    bool readExactly(unsigned char* p, std::size_t n)
    {
        std::size_t got = 0;
        while (got < n) {
            pollfd q{mFd, POLLIN, 0};
            if (::poll(&q, 1, 2000) <= 0) return false;
            const ssize_t r = ::recv(mFd, p + got, n - got, 0);
            if (r <= 0) return false;
            got += std::size_t(r);
        }
        return true;
    }
    int mFd = -1;
    bool mOk = false;
};

// Debian's TrackerClient streams TRANSFORMs at 50 fps: tip (50cosφ, 50sinφ, 50cosφ),
// φ = 0, 0.2, ... (its GetRandomTestMatrix). The bridge receives them and answers.
TEST(Igtl, DebianTrackerClientDrivesTheServer)
{
#ifndef VOXHAP_IGTL_TRACKER_CLIENT
    VOXHAP_REQUIRE(false,
        "Debian's TrackerClient example (openigtlink-examples, which tools/setup.sh installs) when this was "
        "configured");
#else
    IgtlDevice dev(anyPort(), DeviceLimits{});
    const pid_t child = ::fork();
    if (child == 0) {
        ::freopen("/dev/null", "w", stdout);
        ::execl(VOXHAP_IGTL_TRACKER_CLIENT, "TrackerClient", "127.0.0.1", std::to_string(dev.port()).c_str(), "50",
            static_cast<char*>(nullptr));
        ::_exit(127);
    }
    ASSERT_GT(child, 0);
    const bool got = waitFor([&] { return dev.counters().poses.load() >= 5; });
    const DeviceReading r = dev.read(0.0);
    ::kill(child, SIGTERM);
    ::waitpid(child, nullptr, 0);
    ASSERT_TRUE(got) << "poses received: " << dev.counters().poses.load();
    EXPECT_GE(dev.counters().forcesSent.load() + 0, 1);
    EXPECT_TRUE(r.valid);
    // The client's path: x = z = 50cosφ and x² + y² = 50² (float matrix: 1e-3 mm).
    EXPECT_NEAR(r.tip.x(), r.tip.z(), 1e-3);
    EXPECT_NEAR(std::hypot(r.tip.x(), r.tip.y()), 50.0, 1e-3);
    EXPECT_NEAR(r.direction.norm(), 1.0, 1e-12);
    EXPECT_TRUE(waitFor([&] { return !dev.connected(); }));
    EXPECT_TRUE(dev.read(0.0).lost);
#endif
}

// Each kind of bad input: the server drops that client, stays alive, keeps its last
// good pose, and the next client is served.
TEST(Igtl, MalformedInputLeavesTheServerAlive)
{
    IgtlDevice dev(anyPort(), DeviceLimits{});
    const Vec3d good(1.0, 2.0, 3.0);
    {
        RawClient c(dev.port());
        ASSERT_TRUE(c.ok());
        c.sendPose(good);
        double f[3];
        ASSERT_TRUE(c.readForce(f));
        EXPECT_EQ(f[0], 0.0); // nothing written yet
    }
    ASSERT_TRUE(waitFor([&] { return !dev.connected(); })); // the server has let the first client go
    std::vector<unsigned char> garbage(300);
    for (std::size_t i = 0; i < garbage.size(); ++i) garbage[i] = static_cast<unsigned char>(i * 37 + 11);
    unsigned char huge[58] = {0, 1, 'T', 'R', 'A', 'N', 'S', 'F', 'O', 'R', 'M'};
    huge[42] = 0x00, huge[43] = 0x00, huge[44] = 0x01; // body size 2^40 bytes
    const long rejectedBefore = dev.counters().rejected.load();
    for (int kind = 0; kind < 4; ++kind) {
        const long connections = dev.counters().connections.load();
        RawClient c(dev.port());
        ASSERT_TRUE(c.ok());
        ASSERT_TRUE(waitFor([&] { return dev.counters().connections.load() > connections; })); // this client, accepted
        if (kind == 0) c.send(garbage.data(), garbage.size());                                 // garbage
        if (kind == 1) c.send(huge, sizeof huge);                                              // a huge body size
        if (kind == 2) c.sendPose(Vec3d(99.0, 99.0, 99.0), true);                              // a bad CRC
        if (kind == 3) c.send(huge, 20), c.close(); // half a header, then gone
        EXPECT_TRUE(waitFor([&] { return !dev.connected(); })) << "kind " << kind;
        c.close();
        const DeviceReading r = dev.read(0.0);
        EXPECT_EQ(r.tip, Vec3d(good)) << "kind " << kind; // no garbage pose got through
    }
    EXPECT_GE(dev.counters().rejected.load() - rejectedBefore, 3); // garbage, size, CRC (the half header is a hang-up)
    RawClient again(dev.port());
    again.sendPose(Vec3d(4.0, 5.0, 6.0));
    double f[3];
    EXPECT_TRUE(again.readForce(f));
    EXPECT_TRUE(waitFor([&] { return dev.read(0.0).tip == Vec3d(4.0, 5.0, 6.0); }));
}

// In the ligament the force is large; when the client goes away the servo's next
// tick writes zero (DeviceReading::lost → gain 0 at once).
TEST(Igtl, DisconnectZeroesTheForceWithinOneTick)
{
    const SceneInstance inst(loadScene("lumbar-puncture"), nullptr, volume::TissueTable::builtin());
    auto model = inst.makeModel();
    IgtlDevice dev(anyPort(), model->device());
    ServoLoop loop(*model, dev);
    auto client = std::make_unique<RawClient>(dev.port());
    const Vec3d e = inst.entry(), u = (inst.target() - inst.entry()).normalized();
    for (double d = -5.0; d <= 20.0; d += 0.5) { // into the ligament along the path
        client->sendPose(e + d * u, false, u);
        double f[3];
        ASSERT_TRUE(client->readForce(f));
        loop.runTicks(1);
    }
    EXPECT_GT(loop.lastForceN(), 0.0);
    client.reset();
    ASSERT_TRUE(waitFor([&] { return !dev.connected(); }));
    loop.runTicks(1);
    EXPECT_EQ(loop.lastForceN(), 0.0);
}

} // namespace
} // namespace voxhap::haptic

namespace voxhap::haptic {
namespace {

/// The connection policy's clock, moved by the tests (IgtlOptions::clock).
std::atomic<double> gPolicyNow{0.0};
double policyNow() { return gPolicyNow.load(); }

IgtlOptions policyClock()
{
    IgtlOptions o = anyPort();
    o.clock = policyNow;
    gPolicyNow.store(0.0);
    return o;
}

// A connection that never speaks holds the only client slot until the
// first-message deadline (2 s on the policy clock), then is dropped.
TEST(IgtlPolicy, SilentNewcomerIsDroppedAtTheFirstMessageDeadline)
{
    IgtlDevice dev(policyClock(), DeviceLimits{});
    RawClient silent(dev.port());
    ASSERT_TRUE(silent.ok());
    ASSERT_TRUE(waitFor([&] { return dev.counters().connections.load() == 1; }));
    gPolicyNow.store(1.9); // within the deadline
    ASSERT_TRUE(waitFor([&] { return dev.connected(); }));
    EXPECT_EQ(dev.counters().timeouts.load(), 0);
    gPolicyNow.store(2.1);
    ASSERT_TRUE(waitFor([&] { return dev.counters().timeouts.load() == 1; }));
    EXPECT_TRUE(waitFor([&] { return !dev.connected(); }));
    EXPECT_TRUE(dev.read(0.0).lost); // the force goes to zero at once
}

// A client that sent a pose and then went quiet is dropped after 5 s of silence.
TEST(IgtlPolicy, IdleClientIsDroppedAfterItsTimeout)
{
    IgtlDevice dev(policyClock(), DeviceLimits{});
    RawClient client(dev.port());
    client.sendPose(Vec3d(1, 2, 3));
    ASSERT_TRUE(waitFor([&] { return dev.counters().poses.load() == 1; }));
    gPolicyNow.store(4.9);
    ASSERT_TRUE(waitFor([&] { return dev.connected(); }));
    EXPECT_EQ(dev.counters().timeouts.load(), 0);
    gPolicyNow.store(5.1);
    ASSERT_TRUE(waitFor([&] { return dev.counters().timeouts.load() == 1; }));
}

// One controlling client: a newcomer is refused while the client is alive, and
// takes over once the client has been silent longer than 0.25 s.
TEST(IgtlPolicy, NewcomerIsRefusedByALiveClientAndReplacesASilentOne)
{
    IgtlDevice dev(policyClock(), DeviceLimits{});
    RawClient first(dev.port());
    first.sendPose(Vec3d(1, 2, 3));
    ASSERT_TRUE(waitFor([&] { return dev.counters().poses.load() == 1; }));
    gPolicyNow.store(0.1); // the first client spoke 0.1 s ago
    RawClient second(dev.port());
    ASSERT_TRUE(waitFor([&] { return dev.counters().refused.load() == 1; }));
    EXPECT_EQ(dev.counters().connections.load(), 1);
    gPolicyNow.store(0.4); // silent for 0.4 s
    RawClient third(dev.port());
    ASSERT_TRUE(waitFor([&] { return dev.counters().replaced.load() == 1; }));
    EXPECT_EQ(dev.counters().connections.load(), 2);
    third.sendPose(Vec3d(4, 5, 6));
    ASSERT_TRUE(waitFor([&] { return dev.counters().poses.load() == 2; }));
    EXPECT_EQ(dev.read(0.0).tip, Vec3d(4, 5, 6)); // the newcomer controls the device
}

} // namespace
} // namespace voxhap::haptic

namespace voxhap::haptic {
namespace {

void putBigEndian(std::vector<unsigned char>& out, std::uint64_t v, int bytes)
{
    for (int i = bytes - 1; i >= 0; --i) out.push_back(static_cast<unsigned char>(v >> (8 * i)));
}

void putFloat(std::vector<unsigned char>& out, float f)
{
    std::uint32_t bits;
    std::memcpy(&bits, &f, 4);
    putBigEndian(out, bits, 4);
}

/// A header-version-2 TRANSFORM (OpenIGTLink protocol 3) built byte for byte from
/// the published layout ("Overview of Version 3 Protocol"; igtl_extended_header):
/// 58-byte header, a 12-byte extended header, the 48-byte matrix, and a metadata
/// header and body with @p metadata's key/value pairs. The CRC-64 (the library's
/// crc64, ECMA-182) covers the whole body. @p mutate may damage the body after the
/// CRC is computed (a bit flip) or before (an inconsistent size with a valid CRC).
std::vector<unsigned char> version2Transform(const Vec3d& tip,
    const std::vector<std::pair<std::string, std::string>>& metadata,
    const std::function<void(std::vector<unsigned char>&)>& beforeCrc = {})
{
    std::vector<unsigned char> content;
    const float r[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}; // R11 R21 R31 R12 R22 R32 R13 R23 R33: the needle along z
    for (const float x : r) putFloat(content, x);
    for (int i = 0; i < 3; ++i) putFloat(content, float(tip[i]));
    std::vector<unsigned char> metaHeader, metaBody;
    putBigEndian(metaHeader, metadata.size(), 2);
    for (const auto& [k, v] : metadata) {
        putBigEndian(metaHeader, k.size(), 2);
        putBigEndian(metaHeader, 3, 2); // VALUE_ENCODING: US-ASCII (IANA MIBenum 3)
        putBigEndian(metaHeader, v.size(), 4);
        metaBody.insert(metaBody.end(), k.begin(), k.end());
        metaBody.insert(metaBody.end(), v.begin(), v.end());
    }
    std::vector<unsigned char> body;
    putBigEndian(body, 12, 2);                                       // EXT_HEADER_SIZE
    putBigEndian(body, metadata.empty() ? 0 : metaHeader.size(), 2); // METADATA_HEADER_SIZE
    putBigEndian(body, metaBody.size(), 4);                          // METADATA_SIZE
    putBigEndian(body, 42, 4);                                       // MSG_ID
    body.insert(body.end(), content.begin(), content.end());
    if (!metadata.empty()) {
        body.insert(body.end(), metaHeader.begin(), metaHeader.end());
        body.insert(body.end(), metaBody.begin(), metaBody.end());
    }
    if (beforeCrc) beforeCrc(body);
    std::vector<unsigned char> msg;
    putBigEndian(msg, 2, 2); // header version 2
    const char type[12] = "TRANSFORM";
    msg.insert(msg.end(), type, type + 12);
    const char device[20] = "Needle";
    msg.insert(msg.end(), device, device + 20);
    putBigEndian(msg, 0, 8); // TIME_STAMP unused
    putBigEndian(msg, body.size(), 8);
    putBigEndian(msg, crc64(body.data(), body.size(), 0), 8);
    msg.insert(msg.end(), body.begin(), body.end());
    return msg;
}

// Issue 20 item 6: OpenIGTLink 3 clients send header version 2. Its pose is read
// with and without metadata; a flipped bit (bad CRC) and section sizes that do not
// add up (with a valid CRC) are refused, the server staying alive for the next client.
TEST(IgtlVersion2, ExtendedHeaderAndMetadataAreRead)
{
    IgtlDevice dev(anyPort(), DeviceLimits{});
    {
        RawClient c(dev.port());
        const auto m = version2Transform(Vec3d(1.5, -2.0, 30.0), {});
        c.send(m.data(), m.size());
        double f[3];
        ASSERT_TRUE(c.readForce(f)) << "no reply to a version 2 TRANSFORM";
        EXPECT_EQ(dev.read(0.0).tip, Vec3d(1.5, -2.0, 30.0));
        const auto withMeta =
            version2Transform(Vec3d(4.0, 5.0, 6.0), {{"Source", "tracker"}, {"Status", "OK"}, {"Empty", ""}});
        c.send(withMeta.data(), withMeta.size());
        ASSERT_TRUE(c.readForce(f)) << "no reply to a version 2 TRANSFORM with metadata";
        EXPECT_EQ(dev.read(0.0).tip, Vec3d(4.0, 5.0, 6.0));
        EXPECT_EQ(dev.read(0.0).direction, Vec3d(0.0, 0.0, 1.0));
    }
    ASSERT_TRUE(waitFor([&] { return !dev.connected(); }));
    const std::vector<std::function<std::vector<unsigned char>()>> damaged{
        [] { // a bit flipped in the matrix after the CRC
            auto m = version2Transform(Vec3d(9, 9, 9), {{"k", "v"}});
            m[58 + 12 + 40] ^= 0x10;
            return m;
        },
        [] { // METADATA_SIZE one larger than the metadata (valid CRC)
            return version2Transform(Vec3d(9, 9, 9), {{"k", "v"}}, [](auto& b) { b[7] += 1; });
        },
        [] { // EXT_HEADER_SIZE below the 12 bytes of its own fields (valid CRC)
            return version2Transform(Vec3d(9, 9, 9), {}, [](auto& b) { b[1] = 8; });
        },
        [] { // INDEX_COUNT that disagrees with METADATA_HEADER_SIZE (valid CRC)
            return version2Transform(Vec3d(9, 9, 9), {{"k", "v"}}, [](auto& b) { b[12 + 48 + 1] = 5; });
        },
    };
    for (std::size_t i = 0; i < damaged.size(); ++i) {
        const long rejected = dev.counters().rejected.load();
        RawClient c(dev.port());
        const auto m = damaged[i]();
        c.send(m.data(), m.size());
        EXPECT_TRUE(waitFor([&] { return dev.counters().rejected.load() == rejected + 1; })) << "case " << i;
        EXPECT_TRUE(waitFor([&] { return !dev.connected(); })) << "case " << i;
        EXPECT_EQ(dev.read(0.0).tip, Vec3d(4.0, 5.0, 6.0)) << "case " << i << ": a damaged pose got through";
    }
}

} // namespace
} // namespace voxhap::haptic
