// SPDX-License-Identifier: Apache-2.0
/// @file ViewFrame.cpp
#include "render/views/ViewFrame.h"

#include "core/Errors.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace voxhap::render {

Vec2d ViewFrame::toPixel(const Vec3d& world) const
{
    const Vec3d d = world - origin;
    return {d.dot(right) / pixelMm, d.dot(down) / pixelMm};
}

Vec3d ViewFrame::toWorld(const Vec2d& px) const { return origin + pixelMm * (px.x() * right + px.y() * down); }

void viewAxes(ViewKind v, Vec3d& right, Vec3d& down)
{
    switch (v) {
    case ViewKind::Axial: // from the feet: left (+x) right, posterior (+y) down
        right = Vec3d(1, 0, 0), down = Vec3d(0, 1, 0);
        return;
    case ViewKind::Sagittal: // from the patient's left: posterior (+y) right, inferior (−z) down
        right = Vec3d(0, 1, 0), down = Vec3d(0, 0, -1);
        return;
    case ViewKind::Coronal: // from the front: left (+x) right, inferior (−z) down
    case ViewKind::ThreeD:
        right = Vec3d(1, 0, 0), down = Vec3d(0, 0, -1);
        return;
    }
}

ViewFrame viewFrame(ViewKind v, const WorldBounds& box, const Vec3d& through, double pixelMm, int maxPixels)
{
    if (!(pixelMm > 0.0) || !std::isfinite(pixelMm)) throw ValueError("view: pixel size must be positive");
    if (!((box.max - box.min).array() > 0.0).all()) throw ValueError("view: empty field of view");
    ViewFrame f;
    f.kind = v;
    viewAxes(v, f.right, f.down);
    f.normal = f.right.cross(f.down);
    // Extent of the box along the image axes: its corners projected.
    double lo[2] = {std::numeric_limits<double>::max(), std::numeric_limits<double>::max()};
    double hi[2] = {-lo[0], -lo[1]};
    for (int c = 0; c < 8; ++c) {
        const Vec3d corner((c & 1) ? box.max.x() : box.min.x(), (c & 2) ? box.max.y() : box.min.y(),
            (c & 4) ? box.max.z() : box.min.z());
        const double a[2] = {corner.dot(f.right), corner.dot(f.down)};
        for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], a[k]), hi[k] = std::max(hi[k], a[k]);
    }
    const double extent = std::max(hi[0] - lo[0], hi[1] - lo[1]);
    f.pixelMm = std::max(pixelMm, extent / double(std::max(1, maxPixels)));
    f.width = std::max(1, int(std::ceil((hi[0] - lo[0]) / f.pixelMm - 1e-9)));
    f.height = std::max(1, int(std::ceil((hi[1] - lo[1]) / f.pixelMm - 1e-9)));
    // Pixel (0, 0) covers [lo, lo + pixel) along both axes; its centre is half a pixel in.
    f.origin =
        (lo[0] + 0.5 * f.pixelMm) * f.right + (lo[1] + 0.5 * f.pixelMm) * f.down + through.dot(f.normal) * f.normal;
    return f;
}

char directionLetter(const Vec3d& d)
{
    int axis = 0;
    d.cwiseAbs().maxCoeff(&axis);
    static constexpr char kPositive[] = {'L', 'P', 'S'}, kNegative[] = {'R', 'A', 'I'};
    return d[axis] >= 0.0 ? kPositive[axis] : kNegative[axis];
}

OrientationLetters orientationLetters(const ViewFrame& f)
{
    return {directionLetter(-f.right), directionLetter(f.right), directionLetter(-f.down), directionLetter(f.down)};
}

} // namespace voxhap::render
