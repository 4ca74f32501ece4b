// SPDX-License-Identifier: Apache-2.0
/// @file Draw.cpp
#include "render/raster/Draw.h"

#include "render/raster/BitmapFont.h"

#include <algorithm>
#include <cmath>

namespace voxhap::render {

namespace {

/// Paint every pixel whose centre lies within half the stroke width of @p p
/// (a one-pixel stroke paints the nearest pixel).
void stamp(Image& img, const Vec2d& p, const Stroke& s)
{
    const double r = 0.5 * std::max(1.0, s.widthPx);
    if (r <= 0.5) {
        img.blend(int(std::lround(p.x())), int(std::lround(p.y())), s.colour, s.alpha);
        return;
    }
    const int x0 = int(std::ceil(p.x() - r)), x1 = int(std::floor(p.x() + r));
    const int y0 = int(std::ceil(p.y() - r)), y1 = int(std::floor(p.y() + r));
    for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
            if ((Vec2d(x, y) - p).squaredNorm() <= r * r) img.blend(x, y, s.colour, s.alpha);
        }
    }
}

/// The part [t0, t1] (fractions of a→b) of a segment inside the box [lo, hi]
/// (Liang–Barsky); false if none.
bool clipSegment(const Vec2d& a, const Vec2d& b, const Vec2d& lo, const Vec2d& hi, double& t0, double& t1)
{
    t0 = 0.0, t1 = 1.0;
    const Vec2d d = b - a;
    for (int k = 0; k < 2; ++k) {
        const double p[2] = {-d[k], d[k]};
        const double q[2] = {a[k] - lo[k], hi[k] - a[k]};
        for (int e = 0; e < 2; ++e) {
            if (p[e] == 0.0) {
                if (q[e] < 0.0) return false;
                continue;
            }
            const double r = q[e] / p[e];
            if (p[e] < 0.0)
                t0 = std::max(t0, r);
            else
                t1 = std::min(t1, r);
        }
    }
    return t0 <= t1;
}

} // namespace

void drawLine(Image& img, const Vec2d& a, const Vec2d& b, const Stroke& s)
{
    const double len = (b - a).norm();
    if (!std::isfinite(len)) return;
    // Only the part over the image (plus the stroke) is stamped: a path seen
    // almost end-on can project far outside.
    const double margin = s.widthPx + 2.0;
    double t0 = 0.0, t1 = 1.0;
    if (!clipSegment(a, b, Vec2d(-margin, -margin), Vec2d(img.width() + margin, img.height() + margin), t0, t1)) return;
    // Dashes: n of them, the first starting at a and the last ending at b.
    double period = 0.0, on = 0.0;
    if (s.dashPx > 0.0 && len > 3.0 * s.dashPx) {
        on = s.dashPx;
        const int n = std::max(2, int(std::lround((len + s.dashPx) / (2.0 * s.dashPx))));
        period = (len - on) / double(n - 1);
    }
    // A translucent stroke goes through a mask first, so that pixels stamped
    // several times are blended once.
    const bool translucent = s.alpha < 1.0;
    Image mask;
    Stroke st = s;
    if (translucent) {
        mask = Image(img.width(), img.height());
        st.colour = {255, 255, 255};
        st.alpha = 1.0;
    }
    Image& target = translucent ? mask : img;
    const int steps = std::max(1, int(std::ceil((t1 - t0) * len / 0.25))); // quarter-pixel steps: no gaps
    for (int i = 0; i <= steps; ++i) {
        const double f = t0 + (t1 - t0) * double(i) / double(steps);
        const double t = f * len;
        if (period > 0.0 && std::fmod(t, period) > on && t < len - on) continue;
        stamp(target, a + (b - a) * f, st);
    }
    if (translucent) {
        for (int y = 0; y < img.height(); ++y) {
            for (int x = 0; x < img.width(); ++x) {
                if (mask.at(x, y).r) img.blend(x, y, s.colour, s.alpha);
            }
        }
    }
}

void drawRing(Image& img, const Vec2d& centre, double radiusPx, const Stroke& s)
{
    const int steps = std::max(16, int(std::ceil(2.0 * 3.14159265358979 * radiusPx / 0.25)));
    Stroke st = s;
    st.alpha = 1.0; // rings are small: overlapping stamps at full opacity are fine
    for (int i = 0; i < steps; ++i) {
        const double a = 2.0 * 3.14159265358979 * double(i) / double(steps);
        stamp(img, centre + radiusPx * Vec2d(std::cos(a), std::sin(a)), st);
    }
}

void fillDisc(Image& img, const Vec2d& centre, double radiusPx, Rgb colour, double alpha)
{
    const int x0 = int(std::floor(centre.x() - radiusPx)), x1 = int(std::ceil(centre.x() + radiusPx));
    const int y0 = int(std::floor(centre.y() - radiusPx)), y1 = int(std::ceil(centre.y() + radiusPx));
    for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
            if ((Vec2d(x, y) - centre).squaredNorm() <= radiusPx * radiusPx) img.blend(x, y, colour, alpha);
        }
    }
}

int textWidth(std::string_view text, int scale)
{
    return text.empty() ? 0 : (int(text.size()) * kGlyphAdvance - 1) * scale;
}

int textHeight(int scale) { return kGlyphHeight * scale; }

void drawText(Image& img, int x, int y, std::string_view text, Rgb colour, int scale, bool shadow)
{
    scale = std::max(1, scale);
    const auto glyphs = [&](int ox, int oy, Rgb c) {
        int gx = ox;
        for (const char ch : text) {
            const auto rows = glyphRows(ch);
            for (int r = 0; r < kGlyphHeight; ++r) {
                for (int col = 0; col < kGlyphWidth; ++col) {
                    if (rows[std::size_t(r)] & (0b10000 >> col)) {
                        img.fill(gx + col * scale, oy + r * scale, gx + (col + 1) * scale, oy + (r + 1) * scale, c);
                    }
                }
            }
            gx += kGlyphAdvance * scale;
        }
    };
    if (shadow) glyphs(x + scale, y + scale, Rgb{0, 0, 0});
    glyphs(x, y, colour);
}

} // namespace voxhap::render
