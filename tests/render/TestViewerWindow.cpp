// SPDX-License-Identifier: Apache-2.0
/// @file TestViewerWindow.cpp
/// @brief The viewer's X11 window under Xvfb, checked through a second X
/// connection as another client would see it: the pixels shown are the image's
/// (channel order and packing), and clicks, wheel steps and keys sent by the X
/// server come back as the viewer's inputs.
/// Built outside the unity batches: Xlib's macros must not reach other tests.

#include "render/viewer/ViewerWindow.h"
#include "render/volume3d/Display.h"

// gtest before Xlib: Xlib.h defines None, which gtest declares as a struct.
#include <gtest/gtest.h>

#include <X11/Xlib.h>
#include <X11/Xutil.h>
#include <X11/keysym.h>

#include <bit>
#include <chrono>

namespace voxhap::render {
namespace {

TEST(ViewerWindow, ShowsTheImageAndReportsClicksWheelAndKeys)
{
    DisplayGuard display;
    if (!display.available()) GTEST_FAIL() << "no display for the window: " << display.why();
    const int w = 120, h = 90;
    ViewerWindow win(w, h, "voxhap test");
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (!win.mapped() && std::chrono::steady_clock::now() < end) win.poll(10);
    ASSERT_TRUE(win.mapped());

    Image img(w, h, Rgb{10, 20, 30});
    img.at(17, 23) = Rgb{200, 100, 50}; // channels distinct, so a swap or shift shows
    win.show(img);

    ::Display* other = XOpenDisplay(nullptr);
    ASSERT_NE(other, nullptr);
    const Window id = win.windowId();
    XImage* shot = XGetImage(other, id, 0, 0, w, h, AllPlanes, ZPixmap);
    ASSERT_NE(shot, nullptr);
    const auto channel = [&](unsigned long pixel, unsigned long mask) {
        return int((pixel & mask) >> std::countr_zero(mask));
    };
    for (const auto& [x, y] : {std::pair{17, 23}, std::pair{0, 0}, std::pair{w - 1, h - 1}}) {
        const unsigned long p = XGetPixel(shot, x, y);
        const Rgb want = img.at(x, y);
        EXPECT_EQ(channel(p, shot->red_mask), want.r) << x << "," << y;
        EXPECT_EQ(channel(p, shot->green_mask), want.g) << x << "," << y;
        EXPECT_EQ(channel(p, shot->blue_mask), want.b) << x << "," << y;
    }
    XDestroyImage(shot);

    // Events as the server delivers them: a left click, a wheel step down, the q key.
    XEvent e{};
    e.xbutton.type = ButtonPress;
    e.xbutton.display = other;
    e.xbutton.window = id;
    e.xbutton.same_screen = True;
    e.xbutton.x = 30, e.xbutton.y = 40, e.xbutton.button = Button1;
    XSendEvent(other, id, True, ButtonPressMask, &e);
    e.xbutton.x = 60, e.xbutton.y = 70, e.xbutton.button = Button5;
    XSendEvent(other, id, True, ButtonPressMask, &e);
    XEvent k{};
    k.xkey.type = KeyPress;
    k.xkey.display = other;
    k.xkey.window = id;
    k.xkey.same_screen = True;
    k.xkey.keycode = XKeysymToKeycode(other, XK_q);
    XSendEvent(other, id, True, KeyPressMask, &k);
    XFlush(other);

    std::vector<WindowInput> got;
    while (got.size() < 3 && std::chrono::steady_clock::now() < end) {
        for (auto& in : win.poll(10)) got.push_back(in);
    }
    XCloseDisplay(other);
    ASSERT_EQ(got.size(), 3u);
    EXPECT_EQ(got[0].kind, WindowInput::Kind::Click);
    EXPECT_EQ(got[0].x, 30);
    EXPECT_EQ(got[0].y, 40);
    EXPECT_EQ(got[1].kind, WindowInput::Kind::Scroll);
    EXPECT_EQ(got[1].steps, -1);
    EXPECT_EQ(got[1].x, 60);
    EXPECT_EQ(got[2].kind, WindowInput::Kind::Key);
    EXPECT_EQ(got[2].key, "q");
}

} // namespace
} // namespace voxhap::render
