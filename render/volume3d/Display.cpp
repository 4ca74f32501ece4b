// SPDX-License-Identifier: Apache-2.0
/// @file Display.cpp
#include "render/volume3d/Display.h"

#include <X11/Xlib.h> // for XOpenDisplay: the check VTK does not make before aborting

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace voxhap::render {

namespace {

/// The first executable called @p name on $PATH, or empty.
std::string findOnPath(const std::string& name)
{
    const char* path = std::getenv("PATH");
    std::string dirs = path ? path : "/usr/bin:/bin";
    std::size_t start = 0;
    while (start <= dirs.size()) {
        const std::size_t colon = std::min(dirs.find(':', start), dirs.size());
        const std::filesystem::path candidate = std::filesystem::path(dirs.substr(start, colon - start)) / name;
        if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
        start = colon + 1;
    }
    return {};
}

} // namespace

bool displayReachable(const std::string& display)
{
    if (display.empty()) return false;
    ::Display* d = XOpenDisplay(display.c_str());
    if (!d) return false;
    XCloseDisplay(d);
    return true;
}

DisplayGuard::DisplayGuard(double startTimeoutS, bool wait) : mTimeoutS(startTimeoutS)
{
    if (const char* current = std::getenv("DISPLAY")) {
        mHadDisplay = true;
        mPreviousDisplay = current;
        if (displayReachable(current)) {
            mKind = DisplayKind::Existing;
            mDisplay = current;
            return;
        }
    }
    launchXvfb();
    if (wait) this->wait();
}

void DisplayGuard::wait()
{
    if (mReport >= 0) awaitXvfb();
}

DisplayGuard::~DisplayGuard()
{
    if (mReport >= 0) { // started, never waited for
        ::close(mReport);
        stopXvfb();
        return;
    }
    if (mKind != DisplayKind::Xvfb) return;
    stopXvfb();
    if (mHadDisplay)
        ::setenv("DISPLAY", mPreviousDisplay.c_str(), 1);
    else
        ::unsetenv("DISPLAY");
}

std::string DisplayGuard::description() const
{
    switch (mKind) {
    case DisplayKind::Existing:
        return "3D view on display " + mDisplay;
    case DisplayKind::Xvfb:
        return "no display: started Xvfb on " + mDisplay + " for the 3D view (stopped on exit)";
    case DisplayKind::Unavailable:
        break;
    }
    return "no display (" + mWhy + "): slices only, through the GL-free path";
}

void DisplayGuard::launchXvfb()
{
    const std::string xvfb = findOnPath("Xvfb");
    if (xvfb.empty()) {
        mWhy = std::string(mHadDisplay ? "$DISPLAY " + mPreviousDisplay + " unreachable" : "$DISPLAY unset") +
            " and Xvfb not installed (Debian package xvfb)";
        return;
    }
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) {
        mWhy = std::string("cannot start Xvfb: pipe: ") + std::strerror(errno);
        return;
    }
    // Everything the child needs is prepared here: after fork() it may only
    // make async-signal-safe calls.
    const std::string fd = std::to_string(fds[1]);
    const pid_t parent = ::getpid();
    const pid_t pid = ::fork();
    if (pid < 0) {
        mWhy = std::string("cannot start Xvfb: fork: ") + std::strerror(errno);
        ::close(fds[0]), ::close(fds[1]);
        return;
    }
    if (pid == 0) {
        // Child: die with the parent, keep quiet, report the display on fds[1].
        ::prctl(PR_SET_PDEATHSIG, SIGTERM);
        if (::getppid() != parent) ::_exit(1);
        ::close(fds[0]);
        ::fcntl(fds[1], F_SETFD, 0); // the one descriptor Xvfb must keep across exec
        const int devnull = ::open("/dev/null", O_RDWR);
        if (devnull >= 0) ::dup2(devnull, 0), ::dup2(devnull, 1), ::dup2(devnull, 2);
        ::execl(xvfb.c_str(), "Xvfb", "-displayfd", fd.c_str(), "-screen", "0", "1280x1024x24", "-nolisten", "tcp",
            "-noreset", static_cast<char*>(nullptr));
        ::_exit(127);
    }
    ::close(fds[1]);
    mXvfb = pid;
    mReport = fds[0];
}

void DisplayGuard::awaitXvfb()
{
    // (-noreset: an X server resets when its last client leaves and refuses
    // connections meanwhile; our own probe below would be such a client.)
    // Xvfb writes its display number and a newline once it accepts connections.
    const int report = mReport;
    mReport = -1;
    const double timeoutS = mTimeoutS;
    std::string number;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeoutS);
    bool done = false;
    while (!done) {
        const auto left =
            std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
        if (left.count() <= 0) break;
        pollfd p{report, POLLIN, 0};
        if (::poll(&p, 1, int(left.count())) <= 0) continue;
        char buf[32];
        const ssize_t n = ::read(report, buf, sizeof buf);
        if (n <= 0) break; // Xvfb exited (or failed to exec)
        for (ssize_t i = 0; i < n && !done; ++i) {
            if (buf[i] == '\n')
                done = true;
            else
                number += buf[i];
        }
    }
    ::close(report);
    if (!done || number.empty()) {
        stopXvfb();
        mWhy = "Xvfb did not start within " + std::to_string(int(timeoutS)) + " s";
        return;
    }
    mDisplay = ":" + number;
    ::setenv("DISPLAY", mDisplay.c_str(), 1);
    if (!displayReachable(mDisplay)) {
        stopXvfb();
        mWhy = "Xvfb started on " + mDisplay + " but does not accept connections";
        mDisplay.clear();
        if (mHadDisplay)
            ::setenv("DISPLAY", mPreviousDisplay.c_str(), 1);
        else
            ::unsetenv("DISPLAY");
        return;
    }
    mKind = DisplayKind::Xvfb;
}

void DisplayGuard::stopXvfb()
{
    if (mXvfb <= 0) return;
    ::kill(mXvfb, SIGTERM);
    // Give it a second to close its sockets, then insist.
    for (int i = 0; i < 100; ++i) {
        if (::waitpid(mXvfb, nullptr, WNOHANG) == mXvfb) {
            mXvfb = -1;
            return;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ::kill(mXvfb, SIGKILL);
    ::waitpid(mXvfb, nullptr, 0);
    mXvfb = -1;
}

} // namespace voxhap::render
