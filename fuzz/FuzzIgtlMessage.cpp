// SPDX-License-Identifier: Apache-2.0
/// @file FuzzIgtlMessage.cpp
/// @brief libFuzzer target: the OpenIGTLink message reader of the device
/// bridge and the pose stream (readTransform, haptic/igtl/detail/IgtlWire.h).
/// The input is a stream of messages, handed over through a local socket pair
/// and read message by message as the servers do, until one drops the link.
/// Each outcome is checked against the header and body decoded here
/// independently: a pose comes only from a TRANSFORM that arrived whole and
/// whose CRC-64 matches, of 48 bytes (header version 1) or with a 48-byte
/// content between a consistent extended header and metadata (header version
/// 2, protocol 3), and it is the translation and the z column as sent
/// (big-endian float32, finite, z column non-zero); bad versions, sizes,
/// section layouts and CRCs are refused as such; another message type is
/// skipped whole (for version 2 once its CRC and sections check), and the
/// next message is read after it. The stream is read twice: as the device
/// bridge reads it (no shaft asked for: a POINT is skipped like any type) and
/// as the pose stream reads it, where a POINT named "voxhap-shaft" is a shaft:
/// its CRC checked in both header versions, its content whole 136-byte points,
/// each position the big-endian float32 triple at byte 100, all finite.

#include "FuzzInput.h"

#include "haptic/igtl/detail/IgtlWire.h"

#include <sys/socket.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

namespace {

using voxhap::Vec3d;
using voxhap::fuzz::finding;
using voxhap::haptic::detail::WireRead;

constexpr std::size_t kHeader = 58;
constexpr std::uint64_t kTransformBody = 48; // 12 float32
constexpr std::uint64_t kMaxBody = 65536;    // the servers' limit

std::uint64_t bigEndian(const std::uint8_t* p, int n)
{
    std::uint64_t v = 0;
    for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
    return v;
}

/// CRC-64 of the OpenIGTLink standard: ECMA-182 polynomial, not reflected, initial value 0.
std::uint64_t crc64(const std::uint8_t* p, std::size_t n)
{
    std::uint64_t crc = 0;
    for (std::size_t i = 0; i < n; ++i) {
        crc ^= std::uint64_t(p[i]) << 56;
        for (int b = 0; b < 8; ++b) crc = (crc >> 63) ? (crc << 1) ^ 0x42F0E1EBA9EA3693ull : crc << 1;
    }
    return crc;
}

double float32(const std::uint8_t* p)
{
    const auto bits = std::uint32_t(bigEndian(p, 4));
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
}

const char* name(WireRead r)
{
    switch (r) {
    case WireRead::Pose:
        return "a pose";
    case WireRead::Skipped:
        return "skipped";
    case WireRead::Shaft:
        return "a shaft";
    case WireRead::BadPose:
        return "a bad pose";
    case WireRead::BadHeader:
        return "a bad header";
    case WireRead::Broken:
        return "broken";
    }
    return "?";
}

/// What reading the message at @p m (with @p left bytes until the stream ends) must give.
struct Expected {
    WireRead read = WireRead::Broken;
    std::size_t bytes = 0; ///< the message's length, header included
    Vec3d tip{0, 0, 0}, direction{0, 0, 0};
    std::vector<Vec3d> shaft;
};

/// A shaft's POINT content: whole points, every position finite.
void expectShaft(const std::uint8_t* c, std::uint64_t size, Expected& e)
{
    constexpr std::uint64_t kPoint = 136, kPosition = 100;
    if (size % kPoint != 0) return; // BadHeader
    for (std::uint64_t i = 0; i < size / kPoint; ++i) {
        const std::uint8_t* p = c + i * kPoint + kPosition;
        e.shaft.emplace_back(float32(p), float32(p + 4), float32(p + 8));
        if (!e.shaft.back().allFinite()) {
            e.read = WireRead::BadPose;
            return;
        }
    }
    e.read = WireRead::Shaft;
}

/// Header version 2's body: extended header (its size >= 12, then metadata header
/// size, metadata size), content, metadata header (count, then 8 bytes per entry),
/// metadata (ASCII key, value per entry). @return the content offset, or -1.
long version2Content(const std::uint8_t* b, std::uint64_t body, std::uint64_t& contentSize)
{
    if (body < 12) return -1;
    const std::uint64_t ext = bigEndian(b, 2), mh = bigEndian(b + 2, 2), ms = bigEndian(b + 4, 4);
    if (ext < 12 || ext + mh + ms > body) return -1;
    contentSize = body - ext - mh - ms;
    if (mh == 0) return ms == 0 ? long(ext) : -1;
    const std::uint8_t* h = b + ext + contentSize;
    if (mh < 2) return -1;
    const std::uint64_t n = bigEndian(h, 2);
    if (mh != 2 + 8 * n) return -1;
    std::uint64_t total = 0;
    for (std::uint64_t i = 0; i < n; ++i) total += bigEndian(h + 2 + 8 * i, 2) + bigEndian(h + 2 + 8 * i + 4, 4);
    if (total != ms) return -1;
    const std::uint8_t* at = h + mh;
    for (std::uint64_t i = 0; i < n; ++i) {
        const std::uint64_t k = bigEndian(h + 2 + 8 * i, 2), v = bigEndian(h + 2 + 8 * i + 4, 4);
        for (std::uint64_t j = 0; j < k; ++j) {
            if (at[j] > 0x7f) return -1;
        }
        at += k + v;
    }
    return long(ext);
}

Expected expect(const std::uint8_t* m, std::size_t left, bool shafts)
{
    Expected e;
    if (left < kHeader) return e; // the stream ends inside the header
    const auto version = unsigned(bigEndian(m, 2));
    const std::string_view type(
        reinterpret_cast<const char*>(m + 2), ::strnlen(reinterpret_cast<const char*>(m + 2), 12));
    const std::uint64_t body = bigEndian(m + 42, 8), crc = bigEndian(m + 50, 8);
    const bool transform = type == "TRANSFORM";
    const std::string_view device(
        reinterpret_cast<const char*>(m + 14), ::strnlen(reinterpret_cast<const char*>(m + 14), 20));
    const bool shaft = shafts && type == "POINT" && device == "voxhap-shaft";
    e.read = WireRead::BadHeader;
    if (version < 1 || version > 2 || body > kMaxBody) return e;
    if (transform && version == 1 && body != kTransformBody) return e;
    e.bytes = kHeader + std::size_t(body);
    if (left < e.bytes) {
        e.read = WireRead::Broken; // the stream ends inside the body
        return e;
    }
    const std::uint8_t* b = m + kHeader;
    if (version == 2) {
        if (crc64(b, std::size_t(body)) != crc) return e; // BadHeader
        std::uint64_t contentSize = 0;
        const long content = version2Content(b, body, contentSize);
        if (content < 0) return e; // BadHeader
        if (shaft) {
            expectShaft(b + content, contentSize, e);
            return e;
        }
        if (!transform) {
            e.read = WireRead::Skipped;
            return e;
        }
        if (contentSize != kTransformBody) return e;
        b += content;
    } else {
        if (shaft) {
            if (crc64(b, std::size_t(body)) == crc) expectShaft(b, body, e);
            return e;
        }
        if (!transform) {
            e.read = WireRead::Skipped;
            return e;
        }
        if (crc64(b, std::size_t(body)) != crc) return e; // BadHeader
    }
    // Column-major rotation, then the translation: z column at 6..8, translation at 9..11.
    for (int i = 0; i < 3; ++i) {
        e.direction[i] = float32(b + 4 * (6 + i));
        e.tip[i] = float32(b + 4 * (9 + i));
    }
    const bool usable = e.tip.allFinite() && e.direction.allFinite() && e.direction.norm() > 1e-6;
    e.read = usable ? WireRead::Pose : WireRead::BadPose;
    return e;
}

/// A socket pair holding the input, its writing end closed: the reader sees the stream, then its end.
struct Stream {
    int fd[2] = {-1, -1};
    Stream(const std::uint8_t* data, std::size_t size)
    {
        if (::socketpair(AF_UNIX, SOCK_STREAM, 0, fd) != 0) finding("no socket pair");
        for (std::size_t sent = 0; sent < size;) {
            const ssize_t n = ::send(fd[1], data + sent, size - sent, MSG_NOSIGNAL);
            if (n <= 0) finding("cannot hand the input to the reader");
            sent += std::size_t(n);
        }
        ::shutdown(fd[1], SHUT_WR);
    }
    ~Stream()
    {
        ::close(fd[0]);
        ::close(fd[1]);
    }
};

/// Reads the input message by message as a server does, each outcome against the model.
void readAll(const std::uint8_t* data, std::size_t size, bool shafts)
{
    Stream stream(data, size);
    std::size_t at = 0;
    const std::string reader = shafts ? " (pose stream)" : " (device bridge)";
    for (int message = 1;; ++message) {
        Vec3d tip(0, 0, 0), direction(0, 0, 0);
        std::vector<Vec3d> shaft;
        const WireRead got = voxhap::haptic::detail::readTransform(
            stream.fd[0], 1.0, kMaxBody, tip, direction, shafts ? &shaft : nullptr);
        const Expected e = expect(data + at, size - at, shafts);
        if (got != e.read) {
            finding(
                "message " + std::to_string(message) + reader + " read as " + name(got) + ", expected " + name(e.read));
        }
        if (got == WireRead::Pose && (tip != e.tip || direction != e.direction)) {
            finding("message " + std::to_string(message) + ": the pose is not the one sent");
        }
        if (got == WireRead::Shaft && shaft != e.shaft) {
            finding("message " + std::to_string(message) + ": the shaft is not the one sent");
        }
        if (got != WireRead::Pose && got != WireRead::BadPose && got != WireRead::Skipped && got != WireRead::Shaft)
            break; // the link drops
        at += e.bytes;
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    if (size > 65536) return 0; // more than a socket buffer holds without a reader
    readAll(data, size, false);
    readAll(data, size, true);
    return 0;
}
