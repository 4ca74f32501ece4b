// SPDX-License-Identifier: Apache-2.0
/// @file ViewFrame.h
/// @brief Where a view's pixels lie in the patient: the plane, its axes, the
/// pixel size, and the mapping between pixels and world LPS millimetres.
///
/// Display convention (radiological, as on a CT console):
/// - **axial**: seen from the patient's feet: the patient's left is on the
///   image right, anterior at the top (letters R | L, A over P);
/// - **coronal**: seen from the front: the patient's left on the image right,
///   superior at the top (R | L, S over I);
/// - **sagittal**: seen from the patient's left: anterior on the image left,
///   superior at the top (A | P, S over I);
/// - **3d**: a parallel projection seen from the front, oriented as coronal.
///
/// Slices are true LPS planes whatever the scanner's axes: an oblique or
/// anisotropic CT is resampled onto square pixels. Pixel centres sit at integer
/// pixel coordinates, x to the right and y down.
#pragma once

#include "core/Math.h"
#include "render/raster/Image.h"
#include "render/views/ViewTypes.h"

namespace voxhap::render {

/// @brief An axis-aligned world box [mm, LPS].
struct WorldBounds {
    Vec3d min{0, 0, 0};
    Vec3d max{0, 0, 0};
};

class ViewFrame {
public:
    ViewKind kind = ViewKind::Axial;
    Vec3d origin{0, 0, 0};     ///< world position of pixel (0, 0)'s centre [mm]
    Vec3d right{1, 0, 0};      ///< unit world direction of increasing x (image right)
    Vec3d down{0, 1, 0};       ///< unit world direction of increasing y (image down)
    Vec3d normal{0, 0, 1};     ///< right × down: away from the viewer
    double pixelMm = 1.0;      ///< pixel size [mm]
    int width = 1, height = 1; ///< [px]

    /// @brief Pixel coordinates of the orthogonal projection of @p world onto the plane.
    Vec2d toPixel(const Vec3d& world) const;
    /// @brief The world point on the plane at pixel coordinates @p px.
    Vec3d toWorld(const Vec2d& px) const;
    /// @brief Signed distance of @p world from the plane along normal [mm].
    double depth(const Vec3d& world) const { return normal.dot(world - origin); }
    /// @brief World position of the image centre (on the plane).
    Vec3d centre() const { return toWorld(Vec2d(0.5 * (width - 1), 0.5 * (height - 1))); }
};

/// @brief The image axes of a view (see the file comment).
void viewAxes(ViewKind v, Vec3d& right, Vec3d& down);

/// @brief The frame of view @p v whose plane passes through @p through and whose
/// pixels cover @p box (projected onto the plane).
/// @param pixelMm   pixel size [mm]; coarsened if a side would exceed @p maxPixels
/// @throw ValueError on a non-positive pixel size or an empty box
ViewFrame viewFrame(ViewKind v, const WorldBounds& box, const Vec3d& through, double pixelMm, int maxPixels = 1024);

/// @brief The patient-direction letter of the LPS axis closest to @p d:
/// L (+x), R (−x), P (+y), A (−y), S (+z), I (−z).
char directionLetter(const Vec3d& d);

/// @brief The letters at the four edges of a view.
struct OrientationLetters {
    char left = '?', right = '?', top = '?', bottom = '?';
};
OrientationLetters orientationLetters(const ViewFrame& f);

} // namespace voxhap::render
