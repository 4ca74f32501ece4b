// SPDX-License-Identifier: Apache-2.0
/// @file ViewerScript.h
/// @brief Input for the viewer: a text file of events, one a line, played as
/// if a user made them (tests, demos, headless snapshots) by ScriptPlayer, and
/// a window's input delivered to the viewer.
///
/// @code
/// # comments and blank lines are skipped
/// key p                  # a key, by its X keysym name
/// click axial 120 130    # a left click in a pane, in that pane image's pixels
/// scroll sagittal -3     # slices along the pane's normal (in the 3d pane: wheel steps, zoom)
/// drag 3d 40 -10         # the left button held and moved by (40, −10) px: rotates the 3d pane
/// release                # the left button released: the drag ends
/// wait-pose 5            # wait up to 5 s for a streamed needle pose (view --listen)
/// sleep 0.5              # seconds
/// @endcode
#pragma once

#include "render/viewer/Viewer.h"
#include "render/viewer/ViewerWindow.h"

#include <chrono>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace voxhap::render {

struct ScriptStep {
    enum class Kind {
        Event,
        WaitPose,
        Sleep
    };
    Kind kind = Kind::Event;
    ViewerEvent event;  ///< Kind::Event
    double seconds = 0; ///< WaitPose (the limit), Sleep
    int line = 0;       ///< in the script, for messages
};

/// @brief Parse a script; @p origin names it in error messages.
/// @throw ValueError "<origin>:<line>: <what is wrong>"
std::vector<ScriptStep> parseViewerScript(std::string_view text, const std::string& origin);

/// @brief Read and parse a script file. @throw IoError if unreadable; ValueError as above
std::vector<ScriptStep> loadViewerScript(const std::filesystem::path& file);

/// @brief Plays a script's steps one at a time, so that a window stays live
/// while a step waits. Time and the count of needle poses received are the
/// caller's (a clock and a pose stream), so that playback is the same with a
/// window, headless, or in a test.
class ScriptPlayer {
public:
    using Clock = std::chrono::steady_clock;
    /// @p origin names the script in messages; @p listening: whether a pose
    /// stream is open (a wait-pose's timeout says when it is not).
    ScriptPlayer(std::vector<ScriptStep> steps, std::string origin, bool listening = false);
    bool done() const { return mNext >= mSteps.size(); }
    /// @brief Run steps until one must wait, at time @p now with @p poses
    /// received so far: events go to @p viewer, a sleep waits its seconds, a
    /// wait-pose waits for a pose after it began. @return false once a step quits
    /// @throw IoError "<origin>:<line>: wait-pose: no needle pose within N s" when one times out
    bool advance(Viewer& viewer, long poses, Clock::time_point now = Clock::now());

private:
    std::vector<ScriptStep> mSteps;
    std::string mOrigin;
    bool mListening;
    std::size_t mNext = 0;
    std::optional<Clock::time_point> mWaitStarted;
    long mPosesAtStart = 0;
};

/// @brief A window's click, wheel, drag, release, key or close, delivered to
/// @p viewer. @return false when it ends the viewer (a quit key, the window closed)
bool deliver(Viewer& viewer, const WindowInput& in);

/// @brief What a run of the viewer needs from its caller.
struct ViewerRunHooks {
    /// Hands the latest streamed needle pose to the viewer; returns the poses received so far.
    std::function<long(Viewer&)> pump = [](Viewer&) { return 0L; };
    std::function<bool()> stop = [] { return false; }; ///< true: end now (an interrupt)
    double timeoutS = 0;                               ///< end after this long; 0: never
};

/// @brief How a run of the viewer ended.
struct ViewerRunEnd {
    long frames = 0; ///< images drawn
    std::string why; ///< "quit", "script done" or "timeout" (and "" when stopped)
};

/// @brief The viewer in @p window until a key or the window ends it, the
/// timeout or stop(): input delivered, the script played once the window is
/// mapped, the 3D pane settled to full quality, a frame shown when it changed.
ViewerRunEnd runInWindow(Viewer& viewer, ViewerWindow& window, ScriptPlayer& script, const ViewerRunHooks& hooks);

/// @brief Headless: the script played to its end (or the timeout, or stop()),
/// then the window image at full quality written to @p png.
/// @throw IoError when a plan save the script asked for failed, or the PNG cannot be written
ViewerRunEnd runToSnapshot(
    Viewer& viewer, ScriptPlayer& script, const ViewerRunHooks& hooks, const std::filesystem::path& png);

} // namespace voxhap::render
