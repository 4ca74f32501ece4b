// SPDX-License-Identifier: Apache-2.0
/// @file PoseStream.h
/// @brief The live needle, streamed from `voxhap serve` to `voxhap view` as
/// OpenIGTLink TRANSFORM messages over TCP.
///
/// Same pose convention as the device bridge (IgtlDevice.h): the transform's
/// translation is the needle tip [mm, LPS] and its third column the needle
/// direction, hub to tip. TRANSFORM carries float32, so a pose arrives rounded
/// to float (about 1e-5 mm at 100 mm from the origin). A bending needle's shaft
/// travels as a POINT message named "voxhap-shaft" (its points hub to tip, in
/// float32) sent just before the TRANSFORM it belongs to; a TRANSFORM without
/// one is a straight needle. Slicer shows that POINT as a list of fiducials.
///
/// The sender is a client that (re)connects by itself and never blocks for
/// long: it belongs on a status or logging thread, never on the servo thread
/// (it allocates, and it makes system calls). The receiver is a one-client
/// server with its own network thread that keeps only the latest pose.
/// Neither pulls in VTK: the viewer (render/) uses the receiver.
#pragma once

#include "core/Math.h"

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace voxhap::haptic {

/// @brief One streamed needle pose.
struct StreamedPose {
    Vec3d tip{0, 0, 0};       ///< [mm, LPS]
    Vec3d direction{0, 0, 1}; ///< unit, hub to tip
    std::vector<Vec3d> shaft; ///< a bending needle's shaft, hub to tip [mm, LPS]; empty: straight
};

/// @brief "HOST:PORT" or "PORT" (host 127.0.0.1) split and checked.
/// @throw ValueError naming @p what on a bad port (not 1..65535) or an empty host
void parseHostPort(const std::string& text, const std::string& what, std::string& host, int& port);

/// @brief Sends poses to a viewer. Connects on first use and after a loss, at
/// most every retryS; a pose sent while disconnected is dropped (the next one
/// replaces it anyway).
/// @warning Not thread-safe: one sending thread. Never call it from the servo thread.
class PoseSender {
public:
    /// @param host IPv4 address (e.g. "127.0.0.1")
    /// @throw ValueError on an address that does not parse
    PoseSender(std::string host, int port, double retryS = 0.5);
    ~PoseSender();
    PoseSender(const PoseSender&) = delete;
    PoseSender& operator=(const PoseSender&) = delete;

    /// @brief Send one pose (its shaft's POINT first, when it has one); false if
    /// it was dropped (not connected, or the socket buffer was full).
    bool send(const StreamedPose& pose);
    bool connected() const { return mFd >= 0; }
    long sent() const { return mSent; }

private:
    bool connectNow();

    std::string mHost;
    int mPort = 0;
    double mRetryS = 0.5;
    int mFd = -1;
    double mLastAttemptS = -1e9;
    long mSent = 0;
};

/// @brief Receives poses: a TCP server (one client at a time) that validates
/// each header before reading a body, as IgtlDevice does, and keeps the latest
/// pose. Other message types are read and ignored.
/// @note latest() and counters are thread-safe; the network thread is internal.
class PoseReceiver {
public:
    /// @param port 0: any free port (see port())
    /// @throw IoError if the port cannot be bound
    explicit PoseReceiver(int port, const std::string& bindAddress = "127.0.0.1");
    ~PoseReceiver();
    PoseReceiver(const PoseReceiver&) = delete;
    PoseReceiver& operator=(const PoseReceiver&) = delete;

    int port() const { return mPort; }
    /// @brief The latest pose, if any arrived.
    std::optional<StreamedPose> latest() const;
    /// @brief Poses received so far (changes whenever latest() does).
    long poses() const { return mPoses.load(); }
    long rejected() const { return mRejected.load(); }
    bool connected() const { return mConnected.load(); }

private:
    void serve() noexcept;
    bool handleMessage(int fd) noexcept; ///< false: drop the connection

    int mListen = -1, mPort = 0;
    std::thread mThread;
    std::atomic<bool> mStop{false}, mConnected{false};
    std::atomic<long> mPoses{0}, mRejected{0};
    mutable std::mutex mMutex; // guards mLatest (never taken by a servo thread)
    std::optional<StreamedPose> mLatest;
    std::vector<Vec3d> mPendingShaft; ///< network thread only: the shaft for the next TRANSFORM
};

} // namespace voxhap::haptic
