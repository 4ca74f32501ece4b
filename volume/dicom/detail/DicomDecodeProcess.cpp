// SPDX-License-Identifier: Apache-2.0
/// @file DicomDecodeProcess.cpp
/// @brief The decoder process: requests (a path) and replies (frames or a
/// refusal) over a socket pair; the child side is a static hook that runs
/// before main when the program is started as a decoder.

#include "volume/dicom/detail/DicomDecodeProcess.h"

#include "core/Errors.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

extern char** environ;

namespace voxhap::volume {

namespace {

/// Set in the decoder's environment; its value is the socket's descriptor.
constexpr const char* kDecoderVariable = "VOXHAP_DICOM_DECODER_FD";

/// A reply's fixed part; then the message (if any), then the samples.
struct DecodeReply {
    std::int32_t ok = 0;
    std::int32_t rows = 0, columns = 0, frames = 0, type = 0, bitsStored = 0, highBit = -1;
    std::uint64_t rawBytes = 0;
    std::uint32_t messageBytes = 0;
};

bool sendAll(int fd, const void* data, std::size_t n)
{
    const char* p = static_cast<const char*>(data);
    while (n > 0) {
        const ssize_t k = ::send(fd, p, n, MSG_NOSIGNAL); // a dead peer is an error, not a SIGPIPE
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) return false;
        p += k;
        n -= std::size_t(k);
    }
    return true;
}

/// Exactly @p n bytes; false at an early end (the peer is gone).
bool receiveAll(int fd, void* data, std::size_t n)
{
    char* p = static_cast<char*>(data);
    while (n > 0) {
        const ssize_t k = ::recv(fd, p, n, 0);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) return false;
        p += k;
        n -= std::size_t(k);
    }
    return true;
}

/// The decoder's loop: a path in, a reply out, until the caller closes.
[[noreturn]] void serveDecodes(int fd)
{
    // GDCM's assertion text and libjpeg's warnings would reach the user's
    // terminal; the caller reports the outcome in its own one line.
    if (const int null = ::open("/dev/null", O_WRONLY); null >= 0) ::dup2(null, STDERR_FILENO);
    // Die by an abort's own signal: no handler of the program (a sanitizer,
    // libFuzzer) takes it for a crash of the program's main job.
    for (const int sig : {SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL}) std::signal(sig, SIG_DFL);
    DicomFrames f;
    for (;;) {
        std::uint32_t length = 0;
        if (!receiveAll(fd, &length, sizeof length)) ::_exit(0);
        std::string path(length, '\0');
        if (!receiveAll(fd, path.data(), length)) ::_exit(0);
        DecodeReply r;
        std::string message;
        try {
            decodeDicomFramesInProcess(path, f);
            r.ok = 1;
            r.rows = f.rows, r.columns = f.columns, r.frames = f.frames;
            r.type = std::int32_t(f.type), r.bitsStored = f.bitsStored, r.highBit = f.highBit;
            r.rawBytes = f.raw.size();
        } catch (const std::exception& e) {
            message = e.what();
            r.messageBytes = std::uint32_t(message.size());
        }
        if (!sendAll(fd, &r, sizeof r) || !sendAll(fd, message.data(), message.size()) ||
            (r.ok && !sendAll(fd, f.raw.data(), f.raw.size()))) {
            ::_exit(1);
        }
    }
}

/// Before main: a program started as a decoder serves decodes and exits;
/// any other program goes on (one getenv).
const bool kDecoderHook = [] {
    if (const char* fd = std::getenv(kDecoderVariable)) serveDecodes(std::atoi(fd));
    return false;
}();

} // namespace

DicomDecodeProcess::~DicomDecodeProcess() { stop(); }

void DicomDecodeProcess::start(const std::filesystem::path& file)
{
    (void)kDecoderHook;
    int pair[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, pair) != 0) {
        throw IoError(file.string() + ": cannot start the decoder (socketpair: " + std::strerror(errno) + ")");
    }
    // The child's end, without close-on-exec, at a descriptor it is told about.
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    constexpr int kChildFd = 3;
    posix_spawn_file_actions_adddup2(&actions, pair[1], kChildFd);
    std::vector<std::string> env;
    for (char** e = environ; *e; ++e) {
        if (std::strncmp(*e, kDecoderVariable, std::strlen(kDecoderVariable)) != 0) env.emplace_back(*e);
    }
    env.push_back(std::string(kDecoderVariable) + "=" + std::to_string(kChildFd));
    std::vector<char*> envp;
    for (auto& e : env) envp.push_back(e.data());
    envp.push_back(nullptr);
    char name[] = "voxhap-dicom-decoder";
    char* argv[] = {name, nullptr};
    const int rc = ::posix_spawn(&mPid, "/proc/self/exe", &actions, nullptr, argv, envp.data());
    posix_spawn_file_actions_destroy(&actions);
    ::close(pair[1]);
    if (rc != 0) {
        ::close(pair[0]);
        mPid = -1;
        throw IoError(file.string() + ": cannot start the decoder (posix_spawn: " + std::strerror(rc) + ")");
    }
    mSocket = pair[0];
}

void DicomDecodeProcess::stop()
{
    if (mSocket >= 0) ::close(mSocket); // the decoder reads end of input and exits
    mSocket = -1;
    if (mPid > 0) {
        int status = 0;
        while (::waitpid(mPid, &status, 0) < 0 && errno == EINTR) { }
    }
    mPid = -1;
}

void DicomDecodeProcess::decode(const std::filesystem::path& file, DicomFrames& f)
{
    if (mSocket < 0) start(file);
    const std::string path = file.string();
    const std::uint32_t length = std::uint32_t(path.size());
    DecodeReply r;
    std::string message;
    bool complete = sendAll(mSocket, &length, sizeof length) && sendAll(mSocket, path.data(), path.size()) &&
        receiveAll(mSocket, &r, sizeof r);
    if (complete && !r.ok) {
        message.resize(r.messageBytes);
        complete = receiveAll(mSocket, message.data(), message.size());
    }
    if (complete && r.ok) {
        f.rows = r.rows, f.columns = r.columns, f.frames = r.frames;
        f.type = SampleType(r.type), f.bitsStored = r.bitsStored, f.highBit = r.highBit;
        f.raw.resize(r.rawBytes);
        complete = receiveAll(mSocket, f.raw.data(), f.raw.size());
    }
    if (!complete) {
        // The decoder died on this file: report how, and start afresh next time.
        const pid_t pid = mPid;
        ::close(mSocket);
        mSocket = -1;
        int status = 0;
        while (pid > 0 && ::waitpid(pid, &status, 0) < 0 && errno == EINTR) { }
        mPid = -1;
        if (pid > 0 && WIFSIGNALED(status)) {
            throw IoError(path + ": (7FE0,0010) PixelData: GDCM aborted while decoding it (signal " +
                std::to_string(WTERMSIG(status)) + "): corrupt or unsupported pixel data");
        }
        throw IoError(path + ": (7FE0,0010) PixelData: the decoder ended without a result");
    }
    if (!r.ok) throw IoError(message);
}

void decodeDicomFrames(const std::filesystem::path& file, DicomFrames& f)
{
    DicomDecodeProcess decoder;
    decoder.decode(file, f);
}

} // namespace voxhap::volume
