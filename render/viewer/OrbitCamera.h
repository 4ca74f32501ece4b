// SPDX-License-Identifier: Apache-2.0
/// @file OrbitCamera.h
/// @brief The 3D pane's camera: a parallel projection that orbits the volume's
/// centre, as a ViewFrame, so that what is drawn over the picture in software
/// (paths, the needle) lands where VTK puts it after any rotation.
///
/// Pure geometry (no VTK): the semantics of VTK's trackball camera style
/// (vtkInteractorStyleTrackballCamera, VTK 9.1): a drag rotates the camera
/// about the focal point, Azimuth about the view up for x and Elevation about
/// the screen's x axis for y, 20 × MotionFactor 10 = 200° across the pane's
/// width or height; a wheel step dollies by 1.1^2 (a parallel projection
/// scales instead: the pixel size divides by 1.21); reset gives back the home
/// frame exactly.
#pragma once

#include "render/views/ViewFrame.h"

namespace voxhap::render {

/// @brief Degrees a drag across the whole pane turns the camera (VTK's trackball camera: 20 × MotionFactor 10).
inline constexpr double kOrbitDegreesPerPane = 200.0;
/// @brief Zoom factor of one wheel step (VTK's trackball camera: Dolly(1.1^(0.2 × MotionFactor 10))).
inline constexpr double kWheelZoom = 1.21;

class OrbitCamera {
public:
    OrbitCamera() = default;
    /// @param home the frame the camera starts at and resets to (its centre is the pivot)
    explicit OrbitCamera(const ViewFrame& home);

    /// @brief The current frame: same size in pixels as home, rotated and zoomed about home's centre.
    const ViewFrame& frame() const { return mFrame; }
    const ViewFrame& home() const { return mHome; }

    /// @brief Rotate the camera about the view up (vtkCamera::Azimuth) [degrees].
    void azimuth(double degrees);
    /// @brief Rotate the camera about the screen's x axis (vtkCamera::Elevation) [degrees].
    void elevation(double degrees);
    /// @brief Magnify by @p factor (> 1 zooms in: the pixel size divides by it).
    void zoom(double factor);
    /// @brief A drag of (@p dx, @p dy) pane pixels (y down), as the trackball camera style turns it.
    void drag(double dx, double dy);
    /// @brief Wheel steps (positive: away from the user, zooms in).
    void wheel(int steps);
    /// @brief Back to the home frame.
    void reset() { mFrame = mHome; }
    /// @brief True while the frame is the home frame.
    bool atHome() const;

private:
    void recentre(const Vec3d& centre);
    ViewFrame mHome, mFrame;
};

} // namespace voxhap::render
