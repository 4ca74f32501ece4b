// SPDX-License-Identifier: Apache-2.0
/// @file DicomDecodeProcess.cpp
/// @brief GDCM's pixel decode in a forked child, its result sent back through
/// a pipe: an assertion inside GDCM or a codec ends the child, not the caller.

#include "volume/DicomPixels.h"

#include "volume/Errors.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <string>

namespace voxhap::volume {

namespace {

/// What the child writes first; then the message (if any), then the samples.
struct Reply {
    std::int32_t ok = 0;
    std::int32_t rows = 0, columns = 0, frames = 0, type = 0, bitsStored = 0;
    std::uint64_t rawBytes = 0;
    std::uint32_t messageBytes = 0;
};

bool writeAll(int fd, const void* data, std::size_t n)
{
    const char* p = static_cast<const char*>(data);
    while (n > 0) {
        const ssize_t k = ::write(fd, p, n);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) return false;
        p += k;
        n -= std::size_t(k);
    }
    return true;
}

/// Read exactly @p n bytes; false at an early end (the child died).
bool readAll(int fd, void* data, std::size_t n)
{
    char* p = static_cast<char*>(data);
    while (n > 0) {
        const ssize_t k = ::read(fd, p, n);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) return false;
        p += k;
        n -= std::size_t(k);
    }
    return true;
}

[[noreturn]] void child(const std::filesystem::path& file, int fd)
{
    // Die by the signal, with no handler of the parent's (a crash reporter,
    // a sanitizer) taking it for a crash of the parent.
    for (const int sig : {SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL}) std::signal(sig, SIG_DFL);
    // GDCM's assertion text and libjpeg's warnings would reach the user's
    // terminal; the parent reports the outcome in its own one line.
    if (const int null = ::open("/dev/null", O_WRONLY); null >= 0) ::dup2(null, STDERR_FILENO);
    Reply r;
    std::string message;
    DicomFrames f;
    try {
        decodeDicomFramesInProcess(file, f);
        r.ok = 1;
        r.rows = f.rows, r.columns = f.columns, r.frames = f.frames;
        r.type = std::int32_t(f.type), r.bitsStored = f.bitsStored;
        r.rawBytes = f.raw.size();
    } catch (const std::exception& e) {
        message = e.what();
        r.messageBytes = std::uint32_t(message.size());
    }
    const bool sent = writeAll(fd, &r, sizeof r) && writeAll(fd, message.data(), message.size()) &&
                      writeAll(fd, f.raw.data(), f.raw.size());
    ::_exit(sent ? 0 : 1); // no atexit handlers, no destructors of the parent's state
}

} // namespace

void decodeDicomFrames(const std::filesystem::path& file, DicomFrames& f)
{
    int fds[2];
    if (::pipe(fds) != 0) throw IoError(file.string() + ": cannot decode (pipe: " + std::strerror(errno) + ")");
    const pid_t pid = ::fork();
    if (pid < 0) {
        ::close(fds[0]);
        ::close(fds[1]);
        throw IoError(file.string() + ": cannot decode (fork: " + std::strerror(errno) + ")");
    }
    if (pid == 0) {
        ::close(fds[0]);
        child(file, fds[1]);
    }
    ::close(fds[1]);
    Reply r;
    std::string message;
    bool complete = readAll(fds[0], &r, sizeof r);
    if (complete && !r.ok) {
        message.resize(r.messageBytes);
        complete = readAll(fds[0], message.data(), message.size());
    }
    if (complete && r.ok) {
        f.rows = r.rows, f.columns = r.columns, f.frames = r.frames;
        f.type = SampleType(r.type), f.bitsStored = r.bitsStored;
        f.raw.resize(r.rawBytes);
        complete = readAll(fds[0], f.raw.data(), f.raw.size());
    }
    ::close(fds[0]);
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (WIFSIGNALED(status)) {
        throw IoError(file.string() + ": (7FE0,0010) PixelData: GDCM aborted while decoding it (signal " +
                      std::to_string(WTERMSIG(status)) + "): corrupt or unsupported pixel data");
    }
    if (!complete) throw IoError(file.string() + ": (7FE0,0010) PixelData: the decoder ended without a result");
    if (!r.ok) throw IoError(message);
}

} // namespace voxhap::volume
