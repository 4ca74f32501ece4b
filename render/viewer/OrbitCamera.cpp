// SPDX-License-Identifier: Apache-2.0
/// @file OrbitCamera.cpp
#include "render/viewer/OrbitCamera.h"

#include <Eigen/Geometry>

#include <cmath>
#include <numbers>

namespace voxhap::render {

namespace {

Vec3d rotated(const Vec3d& v, const Vec3d& axis, double degrees)
{
    return Eigen::AngleAxisd(degrees * std::numbers::pi / 180.0, axis.normalized()) * v;
}

} // namespace

OrbitCamera::OrbitCamera(const ViewFrame& home) : mHome(home), mFrame(home) { }

void OrbitCamera::recentre(const Vec3d& centre)
{
    // Pixel (0, 0)'s centre sits half the image from the centre, along the new axes.
    mFrame.origin =
        centre - mFrame.pixelMm * (0.5 * (mFrame.width - 1) * mFrame.right + 0.5 * (mFrame.height - 1) * mFrame.down);
}

void OrbitCamera::azimuth(double degrees)
{
    // vtkCamera::Azimuth: the position turns about the view up (−down) through
    // the focal point, so the direction of projection and the screen's x axis
    // turn with it; the view up stays.
    const Vec3d c = mFrame.centre(), up = -mFrame.down;
    mFrame.right = rotated(mFrame.right, up, degrees);
    mFrame.normal = rotated(mFrame.normal, up, degrees);
    recentre(c);
}

void OrbitCamera::elevation(double degrees)
{
    // vtkCamera::Elevation: the position turns about −(screen x) through the
    // focal point; OrthogonalizeViewUp then turns the view up with it.
    const Vec3d c = mFrame.centre(), axis = -mFrame.right;
    mFrame.down = rotated(mFrame.down, axis, degrees);
    mFrame.normal = rotated(mFrame.normal, axis, degrees);
    recentre(c);
}

void OrbitCamera::zoom(double factor)
{
    if (!(factor > 0.0) || !std::isfinite(factor)) return;
    const Vec3d c = mFrame.centre();
    mFrame.pixelMm /= factor;
    recentre(c);
}

void OrbitCamera::drag(double dx, double dy)
{
    // vtkInteractorStyleTrackballCamera::Rotate: rxf = dx · (−20 / width) · 10,
    // ryf = dy_vtk · (−20 / height) · 10 with VTK's y up (dy_vtk = −dy here).
    const double rx = -dx * kOrbitDegreesPerPane / double(mFrame.width);
    const double ry = dy * kOrbitDegreesPerPane / double(mFrame.height);
    azimuth(rx);
    elevation(ry);
}

void OrbitCamera::wheel(int steps) { zoom(std::pow(kWheelZoom, double(steps))); }

bool OrbitCamera::atHome() const
{
    return mFrame.origin == mHome.origin && mFrame.right == mHome.right && mFrame.down == mHome.down &&
        mFrame.normal == mHome.normal && mFrame.pixelMm == mHome.pixelMm;
}

} // namespace voxhap::render
