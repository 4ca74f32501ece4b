// SPDX-License-Identifier: Apache-2.0
/// @file ViewerScript.h
/// @brief Synthetic input for the viewer: a text file of events, one a line,
/// played as if a user made them (tests, demos, headless snapshots).
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

#include "render/Viewer.h"

#include <filesystem>
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

} // namespace voxhap::render
