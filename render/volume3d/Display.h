// SPDX-License-Identifier: Apache-2.0
/// @file Display.h
/// @brief An X display for the 3D view, checked before any VTK window exists.
///
/// Debian's VTK 9.1 renders through X11/GLX only, and creating a render window
/// without a reachable X server aborts the process (toolchain.md "Headless
/// rendering"). So: use $DISPLAY if an X server answers there; otherwise start
/// `Xvfb -displayfd N -screen 0 1280x1024x24 -nolisten tcp -noreset` on a free display,
/// point $DISPLAY at it for this process and stop it on destruction. Without
/// Xvfb the slices still render (they need no GL); the 3D view reports why not.
#pragma once

#include <string>
#include <sys/types.h>

namespace voxhap::render {

/// @brief True if an X server accepts a connection at @p display (e.g. ":0").
bool displayReachable(const std::string& display);

/// @brief Where the 3D view's OpenGL comes from.
enum class DisplayKind {
    Existing,    ///< the $DISPLAY the process was given
    Xvfb,        ///< an Xvfb started for this process
    Unavailable, ///< no X server: only the GL-free slice path works
};

/// @brief Makes sure a display is reachable for as long as it lives.
/// @warning Sets $DISPLAY for the whole process (in the constructor, or in
/// wait() for a start begun without waiting): do that before starting threads
/// that read the environment or spawn processes, and keep one at a time.
class DisplayGuard {
public:
    /// @param startTimeoutS how long to wait for Xvfb to report its display [s]
    /// @param wait false: start Xvfb (if one is needed) and return at once; the
    ///        caller goes on with its own work while the server starts, and
    ///        calls wait() before it uses the display (Xvfb takes 0.2–0.4 s to
    ///        accept connections, a share of `voxhap plan`'s 6 s budget).
    /// Never throws: when no display can be had, kind() is Unavailable and why() says why.
    explicit DisplayGuard(double startTimeoutS = 10.0, bool wait = true);
    ~DisplayGuard();
    DisplayGuard(const DisplayGuard&) = delete;
    DisplayGuard& operator=(const DisplayGuard&) = delete;

    /// @brief Finish a start begun with wait = false: wait for Xvfb to accept
    /// connections and point $DISPLAY at it. Does nothing the second time, or
    /// when the guard was made with wait = true.
    void wait();

    DisplayKind kind() const { return mKind; }
    bool available() const { return mKind != DisplayKind::Unavailable; }
    /// @brief The display in use (":N"), empty if none.
    const std::string& display() const { return mDisplay; }
    /// @brief Why there is no display (kind() == Unavailable).
    const std::string& why() const { return mWhy; }
    /// @brief One line for the user: which path the views take.
    std::string description() const;

private:
    void launchXvfb();
    void awaitXvfb();
    void stopXvfb();

    DisplayKind mKind = DisplayKind::Unavailable;
    std::string mDisplay, mWhy;
    std::string mPreviousDisplay;
    bool mHadDisplay = false;
    pid_t mXvfb = -1;
    int mReport = -1;        ///< read end of Xvfb's -displayfd pipe while its start is pending
    double mTimeoutS = 10.0; ///< for awaitXvfb
};

} // namespace voxhap::render
