// SPDX-License-Identifier: Apache-2.0
/// @file ViewerWindow.cpp
#include "render/viewer/ViewerWindow.h"

#include "core/Errors.h"

#include <X11/Xlib.h>
#include <X11/Xutil.h>
#include <poll.h>

#include <bit>
#include <cstdint>
#include <cstdlib>

namespace voxhap::render {

struct ViewerWindow::Impl {
    Display* display = nullptr;
    Window window = 0;
    GC gc = nullptr;
    Visual* visual = nullptr;
    Atom deleteWindow = 0;
    int width = 0, height = 0;
    bool mapped = false;
    unsigned long masks[3] = {0, 0, 0};
    std::vector<std::uint32_t> pixels; ///< what the XImage points at
    XImage* image = nullptr;
};

ViewerWindow::ViewerWindow(int width, int height, const std::string& title) : mImpl(std::make_unique<Impl>())
{
    Impl& m = *mImpl;
    m.width = width, m.height = height;
    m.display = XOpenDisplay(nullptr);
    if (!m.display) {
        const char* d = std::getenv("DISPLAY");
        throw IoError(std::string("view: cannot open the X display '") + (d ? d : "") + "'");
    }
    const int screen = DefaultScreen(m.display);
    XVisualInfo info;
    if (!XMatchVisualInfo(m.display, screen, 24, TrueColor, &info)) {
        XCloseDisplay(m.display);
        throw IoError("view: the X display has no 24-bit TrueColor visual");
    }
    m.visual = info.visual;
    m.masks[0] = info.red_mask, m.masks[1] = info.green_mask, m.masks[2] = info.blue_mask;
    XSetWindowAttributes a{};
    a.colormap = XCreateColormap(m.display, RootWindow(m.display, screen), m.visual, AllocNone);
    a.background_pixel = 0;
    a.border_pixel = 0;
    a.event_mask =
        ExposureMask | ButtonPressMask | ButtonReleaseMask | Button1MotionMask | KeyPressMask | StructureNotifyMask;
    m.window = XCreateWindow(m.display, RootWindow(m.display, screen), 0, 0, unsigned(width), unsigned(height), 0, 24,
        InputOutput, m.visual, CWColormap | CWBackPixel | CWBorderPixel | CWEventMask, &a);
    XStoreName(m.display, m.window, title.c_str());
    // Fixed size: the panes are laid out once for it.
    XSizeHints* hints = XAllocSizeHints();
    hints->flags = PMinSize | PMaxSize;
    hints->min_width = hints->max_width = width;
    hints->min_height = hints->max_height = height;
    XSetWMNormalHints(m.display, m.window, hints);
    XFree(hints);
    m.deleteWindow = XInternAtom(m.display, "WM_DELETE_WINDOW", False);
    XSetWMProtocols(m.display, m.window, &m.deleteWindow, 1);
    m.gc = XCreateGC(m.display, m.window, 0, nullptr);
    m.pixels.assign(std::size_t(width) * std::size_t(height), 0);
    m.image = XCreateImage(m.display, m.visual, 24, ZPixmap, 0, reinterpret_cast<char*>(m.pixels.data()),
        unsigned(width), unsigned(height), 32, 0);
    XMapWindow(m.display, m.window);
    XFlush(m.display);
}

ViewerWindow::~ViewerWindow()
{
    Impl& m = *mImpl;
    if (m.image) {
        m.image->data = nullptr; // the pixels belong to the vector, not to Xlib
        XDestroyImage(m.image);
    }
    if (m.gc) XFreeGC(m.display, m.gc);
    if (m.window) XDestroyWindow(m.display, m.window);
    if (m.display) XCloseDisplay(m.display);
}

bool ViewerWindow::mapped() const { return mImpl->mapped; }

unsigned long ViewerWindow::windowId() const { return mImpl->window; }

void ViewerWindow::show(const Image& img)
{
    Impl& m = *mImpl;
    // Place each 8-bit channel where the visual's mask says (TrueColor masks are 8 contiguous bits).
    const auto shift = [](unsigned long mask) { return std::countr_zero(mask); };
    const int sr = shift(m.masks[0]), sg = shift(m.masks[1]), sb = shift(m.masks[2]);
    for (int y = 0; y < m.height; ++y) {
        for (int x = 0; x < m.width; ++x) {
            const Rgb c = img.contains(x, y) ? img.at(x, y) : Rgb{};
            m.pixels[std::size_t(y) * std::size_t(m.width) + std::size_t(x)] =
                (std::uint32_t(c.r) << sr) | (std::uint32_t(c.g) << sg) | (std::uint32_t(c.b) << sb);
        }
    }
    XPutImage(m.display, m.window, m.gc, m.image, 0, 0, 0, 0, unsigned(m.width), unsigned(m.height));
    XFlush(m.display);
}

std::vector<WindowInput> ViewerWindow::poll(int timeoutMs)
{
    Impl& m = *mImpl;
    std::vector<WindowInput> out;
    if (!XPending(m.display) && timeoutMs > 0) {
        pollfd p{ConnectionNumber(m.display), POLLIN, 0};
        ::poll(&p, 1, timeoutMs);
    }
    while (XPending(m.display)) {
        XEvent e;
        XNextEvent(m.display, &e);
        switch (e.type) {
        case MapNotify:
            m.mapped = true;
            break;
        case Expose:
            if (e.xexpose.count == 0) {
                XPutImage(m.display, m.window, m.gc, m.image, 0, 0, 0, 0, unsigned(m.width), unsigned(m.height));
            }
            break;
        case ButtonPress: {
            WindowInput in;
            in.x = e.xbutton.x, in.y = e.xbutton.y;
            if (e.xbutton.button == Button1) {
                in.kind = WindowInput::Kind::Click;
            } else if (e.xbutton.button == Button4 || e.xbutton.button == Button5) {
                in.kind = WindowInput::Kind::Scroll;
                in.steps = e.xbutton.button == Button4 ? 1 : -1;
            } else {
                break;
            }
            out.push_back(in);
            break;
        }
        case MotionNotify:
            out.push_back(WindowInput{WindowInput::Kind::Motion, e.xmotion.x, e.xmotion.y, 0, ""});
            break;
        case ButtonRelease:
            if (e.xbutton.button == Button1)
                out.push_back(WindowInput{WindowInput::Kind::Release, e.xbutton.x, e.xbutton.y, 0, ""});
            break;
        case KeyPress: {
            char buf[8];
            KeySym sym = 0;
            XLookupString(&e.xkey, buf, sizeof buf, &sym, nullptr);
            if (const char* name = XKeysymToString(sym))
                out.push_back(WindowInput{WindowInput::Kind::Key, 0, 0, 0, name});
            break;
        }
        case ClientMessage:
            if (Atom(e.xclient.data.l[0]) == m.deleteWindow)
                out.push_back(WindowInput{WindowInput::Kind::Close, 0, 0, 0, ""});
            break;
        default:
            break;
        }
    }
    XFlush(m.display);
    return out;
}

} // namespace voxhap::render
