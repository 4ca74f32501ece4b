// SPDX-License-Identifier: Apache-2.0
/// @file IgtlWire.h
/// @brief What the two OpenIGTLink servers (IgtlDevice, PoseReceiver) share:
/// a loopback/LAN listening socket and one validated TRANSFORM read. Network
/// threads only: these allocate and block (never the servo thread).
#pragma once

#include "core/Math.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace voxhap::haptic::detail {

/// @brief A TCP socket listening on @p bindAddress:@p port (0: any free port).
/// @param what names the server in error messages ("igtl", "pose stream")
/// @param boundPort receives the port actually bound
/// @throw IoError naming the address and the system's reason
int listenTcp(const std::string& bindAddress, int port, const std::string& what, int& boundPort);

/// @brief Read exactly @p n bytes within @p timeoutS; false on timeout, error or close.
bool readExactly(int fd, unsigned char* buf, std::size_t n, double timeoutS);

/// @brief Seconds on the steady clock.
double steadySeconds();

/// @brief The outcome of reading one message.
enum class WireRead {
    Pose,      ///< a TRANSFORM with a finite tip and a non-zero z column
    Shaft,     ///< a POINT named kShaftDeviceName with finite positions (when asked for)
    Skipped,   ///< another message type, read and discarded
    BadPose,   ///< a TRANSFORM whose pose is unusable: count it, keep the link
    BadHeader, ///< version, size or CRC wrong: count it, drop the link
    Broken,    ///< timeout, error or close: drop the link
};

/// @brief Read one message from @p fd. The raw header is checked before
/// anything is allocated (the library trusts headers; toolchain.md): version
/// 1 or 2, body at most @p maxBodyBytes. Header version 1 goes through the
/// library (a TRANSFORM of 48 bytes); header version 2 (protocol 3: extended
/// header, content, metadata) is parsed here from the published layout, its
/// CRC and every section size checked.
/// @param tip, direction for Pose: the translation and the z column as sent (not normalised)
/// @param shaft null: POINT messages are Skipped like any other type; else a
///        POINT whose device name is kShaftDeviceName is read into it (its
///        points' positions, in order) and returns Shaft, its CRC checked in
///        either header version; a POINT of another name is still Skipped.
WireRead readTransform(int fd, double timeoutS, std::uint64_t maxBodyBytes, Vec3d& tip, Vec3d& direction,
    std::vector<Vec3d>* shaft = nullptr) noexcept;

/// The device name of the POINT message that carries a bent needle's shaft,
/// hub to tip, ahead of the TRANSFORM of the same pose (PoseStream.h).
inline constexpr const char* kShaftDeviceName = "voxhap-shaft";
/// The POINT content per point (OpenIGTLink "POINT": NAME char[64], GROUP
/// char[32], RGBA u8[4], XYZ float32[3], RADIUS float32, OWNER char[20]).
inline constexpr std::size_t kPointElementBytes = 136;
inline constexpr std::size_t kPointPositionOffset = 100;

} // namespace voxhap::haptic::detail
