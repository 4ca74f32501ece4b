// SPDX-License-Identifier: Apache-2.0
/// @file ViewerWindow.h
/// @brief The viewer's on-screen window: a plain X11 window that shows an
/// Image and reports clicks, wheel steps and keys.
///
/// Plain Xlib rather than a VTK interactor: the viewer composes its panes in
/// software anyway (the 3D pane comes from an off-screen VTK window), and the
/// caller's own loop polls the window and the pose stream together. This also
/// avoids the VTK 9.1 interactor's exit-time object-factory crash.
#pragma once

#include "render/raster/Image.h"

#include <memory>
#include <string>
#include <vector>

namespace voxhap::render {

/// @brief One input from the window.
struct WindowInput {
    enum class Kind {
        Click,
        Scroll,
        Key,
        Close,
        Motion, ///< the pointer moved with the left button held
        Release ///< the left button went up
    };
    Kind kind = Kind::Key;
    int x = 0, y = 0; ///< Click, Scroll, Motion, Release: window pixels
    int steps = 0;    ///< Scroll: +1 wheel up, −1 wheel down
    std::string key;  ///< Key: X keysym name ("q", "Up", "Escape")
};

class ViewerWindow {
public:
    /// @brief Open a fixed-size window on $DISPLAY.
    /// @throw IoError if no X display can be opened or it has no 24-bit TrueColor visual
    ViewerWindow(int width, int height, const std::string& title);
    ~ViewerWindow();
    ViewerWindow(const ViewerWindow&) = delete;
    ViewerWindow& operator=(const ViewerWindow&) = delete;

    /// @brief Show @p img (the window's size; larger images are cropped).
    void show(const Image& img);
    /// @brief The inputs that arrive within @p timeoutMs (0: only those pending).
    std::vector<WindowInput> poll(int timeoutMs);
    /// @brief True once the window has been mapped (shown) by the X server.
    bool mapped() const;
    /// @brief The X window id (for tests and tools that send it events).
    unsigned long windowId() const;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace voxhap::render
