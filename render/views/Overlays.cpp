// SPDX-License-Identifier: Apache-2.0
/// @file Overlays.cpp
#include "render/views/Overlays.h"

#include "render/raster/Draw.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace voxhap::render {

namespace {

constexpr int kMarginPx = 6;      ///< annotations keep this far from the edges
constexpr double kMarkerPx = 5.0; ///< radius of the entry, target and crossing rings

/// The part of segment a→b (as fractions) within @p slab of the plane, if any.
bool inPlanePart(const ViewFrame& f, const Vec3d& a, const Vec3d& b, double slab, double& t0, double& t1)
{
    const double da = f.depth(a), db = f.depth(b);
    if (std::abs(db - da) < 1e-12) { // parallel to the plane
        t0 = 0.0, t1 = 1.0;
        return std::abs(da) <= slab;
    }
    const double ta = (-slab - da) / (db - da), tb = (slab - da) / (db - da);
    t0 = std::max(0.0, std::min(ta, tb));
    t1 = std::min(1.0, std::max(ta, tb));
    return t0 < t1;
}

/// Where segment a→b crosses the plane, if it does.
std::optional<Vec3d> crossing(const ViewFrame& f, const Vec3d& a, const Vec3d& b)
{
    const double da = f.depth(a), db = f.depth(b);
    if ((da > 0.0 && db > 0.0) || (da < 0.0 && db < 0.0) || da == db) return std::nullopt;
    return a + (b - a) * (da / (da - db));
}

/// A segment: dashed where it lies off the plane, solid and wider where it is
/// within the slab, a filled ring where it crosses.
void drawSegment(
    Image& img, const ViewFrame& f, const Vec3d& a, const Vec3d& b, Rgb colour, double widthPx, const OverlayStyle& s)
{
    drawLine(img, f.toPixel(a), f.toPixel(b), Stroke{colour, widthPx, 6.0, 1.0});
    double t0 = 0.0, t1 = 0.0;
    if (inPlanePart(f, a, b, s.inPlaneMm, t0, t1)) {
        drawLine(
            img, f.toPixel(a + t0 * (b - a)), f.toPixel(a + t1 * (b - a)), Stroke{colour, widthPx + 1.0, 0.0, 1.0});
    }
    if (const auto x = crossing(f, a, b)) {
        drawRing(img, f.toPixel(*x), kMarkerPx, Stroke{colour, 2.0, 0.0, 1.0});
    }
}

void drawCrosshair(Image& img, const Vec2d& c, Rgb colour)
{
    // A gap around the point leaves what it marks visible.
    constexpr double kGap = 8.0;
    const Stroke st{colour, 1.0, 0.0, 0.7};
    drawLine(img, Vec2d(0.0, c.y()), Vec2d(c.x() - kGap, c.y()), st);
    drawLine(img, Vec2d(c.x() + kGap, c.y()), Vec2d(img.width() - 1.0, c.y()), st);
    drawLine(img, Vec2d(c.x(), 0.0), Vec2d(c.x(), c.y() - kGap), st);
    drawLine(img, Vec2d(c.x(), c.y() + kGap), Vec2d(c.x(), img.height() - 1.0), st);
}

std::string formatMm(double mm)
{
    std::ostringstream os;
    os << mm << " mm";
    return os.str();
}

} // namespace

int annotationScale(const Image& img) { return std::min(img.width(), img.height()) >= 400 ? 2 : 1; }

double scaleBarLengthMm(double widthMm)
{
    const double limit = 0.25 * widthMm;
    double best = 0.0;
    for (double decade = 1e-3; decade <= 1e6; decade *= 10.0) {
        for (const double m : {1.0, 2.0, 5.0}) {
            if (m * decade <= limit * (1.0 + 1e-12)) best = m * decade;
        }
    }
    return best;
}

void drawAnnotations(Image& img, const ViewFrame& f, const Overlays& o, const OverlayStyle& s)
{
    const int scale = annotationScale(img);
    const int th = textHeight(scale);
    if (o.letters) {
        const OrientationLetters l = orientationLetters(f);
        const auto letter = [&](char c, int x, int y) { drawText(img, x, y, std::string(1, c), s.letters, scale + 1); };
        const int lw = textWidth("A", scale + 1), lh = textHeight(scale + 1);
        letter(l.left, kMarginPx, (img.height() - lh) / 2);
        letter(l.right, img.width() - kMarginPx - lw, (img.height() - lh) / 2);
        letter(l.top, (img.width() - lw) / 2, kMarginPx);
        letter(l.bottom, (img.width() - lw) / 2, img.height() - kMarginPx - lh);
    }
    if (o.scaleBar) {
        const double lengthMm = scaleBarLengthMm(f.width * f.pixelMm);
        if (lengthMm > 0.0) {
            const double px = lengthMm / f.pixelMm;
            const double y = img.height() - kMarginPx - 2.0;
            const double x0 = kMarginPx;
            const Stroke st{s.text, 2.0, 0.0, 1.0};
            drawLine(img, Vec2d(x0, y), Vec2d(x0 + px, y), st);
            drawLine(img, Vec2d(x0, y - 4.0 * scale), Vec2d(x0, y), st);
            drawLine(img, Vec2d(x0 + px, y - 4.0 * scale), Vec2d(x0 + px, y), st);
            drawText(img, kMarginPx + 2 * scale, int(y) - 5 * scale - th, formatMm(lengthMm), s.text, scale);
        }
    }
    if (!o.title.empty()) drawText(img, kMarginPx, kMarginPx, o.title, s.text, scale);
    if (!o.legend.empty()) drawText(img, kMarginPx, kMarginPx + th + 2 * scale, o.legend, s.text, scale);
}

void drawSliceOverlays(Image& img, const ViewFrame& f, const Overlays& o, const OverlayStyle& s)
{
    if (o.crosshair) drawCrosshair(img, f.toPixel(*o.crosshair), s.crosshair);
    for (const planning::PlannedPath& p : o.paths) {
        drawRing(img, f.toPixel(p.entry), kMarkerPx, Stroke{s.entry, 2.0, 0.0, 1.0});
        drawRing(img, f.toPixel(p.target), kMarkerPx, Stroke{s.target, 2.0, 0.0, 1.0});
        drawSegment(img, f, p.entry, p.target, s.path, 1.0, s);
        if (p.needle) {
            for (const auto& [a, b] : p.needle->segments()) drawSegment(img, f, a, b, s.needle, 2.0, s);
        }
    }
    if (o.needle) {
        for (const auto& [a, b] : o.needle->segments()) drawSegment(img, f, a, b, s.needle, 2.0, s);
        fillDisc(img, f.toPixel(o.needle->tip), 2.5, s.needle);
    }
    drawAnnotations(img, f, o, s);
}

} // namespace voxhap::render
