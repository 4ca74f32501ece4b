// SPDX-License-Identifier: Apache-2.0
/// @file IgtlWire.cpp
/// @brief OpenIGTLink socket and TRANSFORM reading shared by the device bridge
/// and the pose receiver (haptic/igtl/detail/IgtlWire.h).

#include "haptic/igtl/detail/IgtlWire.h"

#include "core/Errors.h"

#include <igtlTransformMessage.h>

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

WireRead readTransform(int fd, double timeoutS, std::uint64_t maxBodyBytes, Vec3d& tip, Vec3d& direction) noexcept
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
    // OpenIGTLink 1.11 reads header version 1 only: on a version 2 header (protocol 3, an
    // extended header before the matrix) its unpacking depends on uninitialised memory.
    if (transform && (version != 1 || bodySize != kTransformBodyBytes)) return WireRead::BadHeader;
    try {
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
