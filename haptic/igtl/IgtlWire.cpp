// SPDX-License-Identifier: Apache-2.0
/// @file IgtlWire.cpp
/// @brief OpenIGTLink socket and TRANSFORM reading shared by the device bridge
/// and the pose receiver (haptic/igtl/detail/IgtlWire.h).

#include "haptic/igtl/detail/IgtlWire.h"

#include "core/Errors.h"

#include <igtlTransformMessage.h>
#include <igtl_util.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <vector>

namespace voxhap::haptic::detail {

namespace {
constexpr std::size_t kHeaderBytes = 58;          // OpenIGTLink v1/v2 header
constexpr std::uint64_t kTransformBodyBytes = 48; // 12 float32
constexpr std::size_t kExtendedHeaderBytes = 12;  // header version 2: the smallest extended header

std::uint64_t bigEndian(const unsigned char* p, int bytes)
{
    std::uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
    return v;
}

float bigEndianFloat(const unsigned char* p)
{
    const auto bits = std::uint32_t(bigEndian(p, 4));
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
}

/// The body of a header-version-2 message (OpenIGTLink protocol 3, "Overview of
/// Version 3 Protocol" and the library's igtl_extended_header; big endian):
///
///   extended header: EXT_HEADER_SIZE u16 (>= 12), METADATA_HEADER_SIZE u16,
///                    METADATA_SIZE u32, MSG_ID u32, then EXT_HEADER_SIZE - 12
///                    bytes a later revision may add (skipped)
///   content:         BODY_SIZE - EXT_HEADER_SIZE - METADATA_HEADER_SIZE - METADATA_SIZE
///   metadata header: INDEX_COUNT u16, then per entry KEY_SIZE u16,
///                    VALUE_ENCODING u16, VALUE_SIZE u32 (2 + 8·INDEX_COUNT bytes)
///   metadata:        per entry the key (ASCII), then the value
///
/// Every size is checked against the body before it is used; the CRC-64 of the
/// header covers the whole body. Metadata is validated and ignored (voxhap reads
/// no key). @return the content's offset and size, or false when inconsistent.
bool splitVersion2Body(const std::vector<unsigned char>& body, std::size_t& contentAt, std::size_t& contentSize)
{
    if (body.size() < kExtendedHeaderBytes) return false;
    const std::uint64_t extSize = bigEndian(&body[0], 2), metaHeaderSize = bigEndian(&body[2], 2),
                        metaSize = bigEndian(&body[4], 4);
    if (extSize < kExtendedHeaderBytes || extSize + metaHeaderSize + metaSize > body.size()) return false;
    contentAt = std::size_t(extSize);
    contentSize = std::size_t(body.size() - extSize - metaHeaderSize - metaSize);
    if (metaHeaderSize == 0) return metaSize == 0;
    const std::size_t metaHeaderAt = contentAt + contentSize;
    if (metaHeaderSize < 2) return false;
    const std::uint64_t count = bigEndian(&body[metaHeaderAt], 2);
    if (metaHeaderSize != 2 + 8 * count) return false;
    std::uint64_t entries = 0;
    for (std::uint64_t i = 0; i < count; ++i) {
        const unsigned char* e = &body[metaHeaderAt + 2 + 8 * i];
        const std::uint64_t keySize = bigEndian(e, 2), valueSize = bigEndian(e + 4, 4);
        entries += keySize + valueSize;
    }
    if (entries != metaSize) return false;
    // Keys are ASCII (the protocol's rule); values may be in any encoding.
    std::size_t at = metaHeaderAt + std::size_t(metaHeaderSize);
    for (std::uint64_t i = 0; i < count; ++i) {
        const unsigned char* e = &body[metaHeaderAt + 2 + 8 * i];
        const std::size_t keySize = std::size_t(bigEndian(e, 2)), valueSize = std::size_t(bigEndian(e + 4, 4));
        for (std::size_t k = 0; k < keySize; ++k) {
            if (body[at + k] > 0x7f) return false;
        }
        at += keySize + valueSize;
    }
    return true;
}

/// A TRANSFORM content (protocol "TRANSFORM": R11 R21 R31 R12 R22 R32 R13 R23 R33 TX TY TZ,
/// float32 big endian): the translation and the third column.
WireRead poseFromTransformContent(const unsigned char* c, Vec3d& tip, Vec3d& direction)
{
    direction = Vec3d(bigEndianFloat(c + 24), bigEndianFloat(c + 28), bigEndianFloat(c + 32));
    tip = Vec3d(bigEndianFloat(c + 36), bigEndianFloat(c + 40), bigEndianFloat(c + 44));
    if (!tip.allFinite() || !direction.allFinite() || !(direction.norm() > 1e-6)) return WireRead::BadPose;
    return WireRead::Pose;
}

/// A POINT content: its points' positions, every one finite.
WireRead shaftFromPointContent(const unsigned char* c, std::size_t size, std::vector<Vec3d>& shaft)
{
    if (size % kPointElementBytes != 0) return WireRead::BadHeader;
    shaft.resize(size / kPointElementBytes);
    for (std::size_t i = 0; i < shaft.size(); ++i) {
        const unsigned char* at = c + i * kPointElementBytes + kPointPositionOffset;
        shaft[i] = Vec3d(bigEndianFloat(at), bigEndianFloat(at + 4), bigEndianFloat(at + 8));
        if (!shaft[i].allFinite()) return WireRead::BadPose;
    }
    return WireRead::Shaft;
}

/// A header-version-2 message, whatever its type: the body read whole (bounded
/// by the caller's maxBodyBytes), its CRC-64 checked (the library's crc64,
/// ECMA-182), its sections split; a TRANSFORM's content is the 48-byte matrix.
WireRead readVersion2(int fd, const unsigned char* header, std::uint64_t bodySize, bool transform, double timeoutS,
    Vec3d& tip, Vec3d& direction, std::vector<Vec3d>* shaft)
{
    std::vector<unsigned char> body(bodySize);
    if (bodySize > 0 && !readExactly(fd, body.data(), body.size(), timeoutS)) return WireRead::Broken;
    if (crc64(body.data(), bodySize, 0) != bigEndian(header + 50, 8)) return WireRead::BadHeader;
    std::size_t contentAt = 0, contentSize = 0;
    if (!splitVersion2Body(body, contentAt, contentSize)) return WireRead::BadHeader;
    if (shaft) return shaftFromPointContent(body.data() + contentAt, contentSize, *shaft);
    if (!transform) return WireRead::Skipped;
    if (contentSize != kTransformBodyBytes) return WireRead::BadHeader;
    return poseFromTransformContent(&body[contentAt], tip, direction);
}

} // namespace

int listenTcp(const std::string& bindAddress, int port, const std::string& what, int& boundPort)
{
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0) throw IoError(what + ": cannot create a socket: " + std::string(std::strerror(errno)));
    const int one = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(std::uint16_t(port));
    if (::inet_pton(AF_INET, bindAddress.c_str(), &addr.sin_addr) != 1) {
        ::close(fd);
        throw IoError(what + ": bad bind address '" + bindAddress + "'");
    }
    // A real backlog: clients that connect while another is served wait to be
    // accepted (and refused or adopted by the server's policy) instead of failing.
    constexpr int kListenBacklog = 16;
    if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 || ::listen(fd, kListenBacklog) != 0) {
        const std::string why = std::strerror(errno);
        ::close(fd);
        throw IoError(what + ": cannot listen on " + bindAddress + ":" + std::to_string(port) + ": " + why);
    }
    socklen_t len = sizeof addr;
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
    boundPort = ntohs(addr.sin_port);
    return fd;
}

double steadySeconds()
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

bool readExactly(int fd, unsigned char* buf, std::size_t n, double timeoutS)
{
    const double end = steadySeconds() + timeoutS;
    std::size_t got = 0;
    while (got < n) {
        const double left = end - steadySeconds();
        if (left <= 0.0) return false;
        pollfd p{fd, POLLIN, 0};
        if (::poll(&p, 1, int(std::ceil(left * 1000.0))) <= 0) return false;
        const ssize_t r = ::recv(fd, buf + got, n - got, 0);
        if (r <= 0) return false;
        got += std::size_t(r);
    }
    return true;
}

WireRead readTransform(int fd, double timeoutS, std::uint64_t maxBodyBytes, Vec3d& tip, Vec3d& direction,
    std::vector<Vec3d>* shaft) noexcept
{
    unsigned char header[kHeaderBytes];
    if (!readExactly(fd, header, kHeaderBytes, timeoutS)) return WireRead::Broken;
    const unsigned version = (unsigned(header[0]) << 8) | header[1];
    char type[13] = {};
    std::memcpy(type, header + 2, 12);
    std::uint64_t bodySize = 0;
    for (int i = 0; i < 8; ++i) bodySize = (bodySize << 8) | header[42 + i];
    if (version < 1 || version > 2 || bodySize > maxBodyBytes) return WireRead::BadHeader;
    const bool transform = std::strncmp(type, "TRANSFORM", 12) == 0;
    char device[21] = {};
    std::memcpy(device, header + 14, 20);
    // The shaft's POINT, when the caller reads shafts; any other POINT is skipped below.
    if (!(shaft && std::strncmp(type, "POINT", 12) == 0 && std::strcmp(device, kShaftDeviceName) == 0)) shaft = nullptr;
    try {
        // OpenIGTLink 1.11 (Debian's) reads header version 1 only: on a version 2 header
        // (protocol 3: an extended header before the content, metadata after it) its
        // unpacking depends on uninitialised memory, so version 2 is read here.
        if (version == 2) return readVersion2(fd, header, bodySize, transform, timeoutS, tip, direction, shaft);
        if (shaft) { // the same layout in both header versions: read here, not through the library
            std::vector<unsigned char> body(bodySize);
            if (bodySize > 0 && !readExactly(fd, body.data(), body.size(), timeoutS)) return WireRead::Broken;
            if (crc64(body.data(), bodySize, 0) != bigEndian(header + 50, 8)) return WireRead::BadHeader;
            return shaftFromPointContent(body.data(), body.size(), *shaft);
        }
        if (transform && bodySize != kTransformBodyBytes) return WireRead::BadHeader;
        if (!transform) { // read and discard, bounded by maxBodyBytes
            std::vector<unsigned char> body(bodySize);
            return bodySize == 0 || readExactly(fd, body.data(), body.size(), timeoutS) ? WireRead::Skipped
                                                                                        : WireRead::Broken;
        }
        auto head = igtl::MessageHeader::New();
        head->InitPack();
        std::memcpy(head->GetPackPointer(), header, kHeaderBytes);
        head->Unpack(); // byte-swaps in place
        auto msg = igtl::TransformMessage::New();
        msg->SetMessageHeader(head);
        msg->AllocatePack();
        if (std::uint64_t(msg->GetPackBodySize()) != bodySize) return WireRead::BadHeader;
        if (!readExactly(fd, static_cast<unsigned char*>(msg->GetPackBodyPointer()), bodySize, timeoutS)) {
            return WireRead::Broken;
        }
        if (!(msg->Unpack(1) & igtl::MessageHeader::UNPACK_BODY)) return WireRead::BadHeader; // CRC mismatch
        igtl::Matrix4x4 m;
        msg->GetMatrix(m);
        tip = Vec3d(m[0][3], m[1][3], m[2][3]);
        direction = Vec3d(m[0][2], m[1][2], m[2][2]);
        if (!tip.allFinite() || !direction.allFinite() || !(direction.norm() > 1e-6)) return WireRead::BadPose;
        return WireRead::Pose;
    } catch (...) {
        return WireRead::Broken;
    }
}

} // namespace voxhap::haptic::detail
