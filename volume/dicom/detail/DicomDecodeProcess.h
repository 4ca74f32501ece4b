// SPDX-License-Identifier: Apache-2.0
/// @file DicomDecodeProcess.h
/// @brief GDCM's pixel decode in a separate process, so that an assertion
/// inside GDCM or one of its codecs ends that process, not the caller.
///
/// Debian's GDCM keeps its assertions, and its codecs (JPEG, JPEG-LS,
/// JPEG 2000, RLE) assert on corrupt streams that no header check can
/// foresee. The decoder is this same program, started afresh (posix_spawn of
/// /proc/self/exe): a static hook in this library turns it into a decoder
/// before main runs. A fresh process, not a fork, because a fork of a
/// threaded process can inherit a lock another thread held (a sanitizer's
/// allocator lock hung a forked child in the fuzzer).
#pragma once

#include "volume/dicom/detail/DicomPixels.h"

#include <sys/types.h>

#include <filesystem>

namespace voxhap::volume {

/// @brief One decoder process, started on first use, serving decodes one at
/// a time. Not thread-safe: callers serialise (FrameSource holds a mutex).
class DicomDecodeProcess {
public:
    DicomDecodeProcess() = default;
    ~DicomDecodeProcess();
    DicomDecodeProcess(const DicomDecodeProcess&) = delete;
    DicomDecodeProcess& operator=(const DicomDecodeProcess&) = delete;

    /// @brief Decode @p file in the decoder process into @p out.
    /// @throw IoError naming the file: GDCM's own refusal, or, when the decoder
    ///        died (an assertion in GDCM), that it aborted; a next call starts a new one
    void decode(const std::filesystem::path& file, DicomFrames& out);

private:
    void start(const std::filesystem::path& file);
    void stop();

    pid_t mPid = -1;
    int mSocket = -1;
};

} // namespace voxhap::volume
