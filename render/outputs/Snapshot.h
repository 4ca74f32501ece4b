// SPDX-License-Identifier: Apache-2.0
/// @file Snapshot.h
/// @brief The planning views of one volume, built for what a request names:
/// a view that is not requested is not set up, and the volume is handed to
/// VTK once (RenderVolume) for all of them. Also the four-view contact sheet.
#pragma once

#include "planning/PlanFile.h"
#include "render/raster/Image.h"
#include "render/views/Overlays.h"
#include "render/views/ViewFrame.h"
#include "render/views/ViewTypes.h"
#include "render/volume3d/VolumeView3d.h"

#include <memory>
#include <optional>
#include <vector>

namespace voxhap::volume {
class TissueTable;
class Volume;
} // namespace voxhap::volume

namespace voxhap::render {

class RenderVolume;

struct RenderRequest {
    std::vector<ViewKind> views{ViewKind::Axial, ViewKind::Sagittal, ViewKind::Coronal, ViewKind::ThreeD};
    BlendMode mode = BlendMode::Colour; ///< of the 3D view
    RayCaster caster = RayCaster::Auto; ///< of the 3D view
    /// Slices' and 3D window; default RenderVolume::defaultWindow: on CT soft
    /// tissue (MIP: bone), on MR the body's robust range, never a CT preset.
    std::optional<WindowLevel> window;
    /// Where the slices cut and the crosshair sits [mm, LPS]; default the first
    /// path's target, else the centre of the volume.
    std::optional<Vec3d> point;
    planning::Plan plan;
    std::optional<planning::NeedlePose> needle;
    double pixelMm = 0.0;         ///< pixel size [mm]; 0: the finest voxel size
    int maxPixels = 768;          ///< largest side of a view [px] (the pixel size grows to fit)
    bool labels = true;           ///< tissue colours on the slices (when the volume has labels)
    bool criticalSurfaces = true; ///< critical structures as surfaces in 3D (when it has labels)
    /// The 3D view's quality: Full for a still picture; Moving (the viewer's
    /// reduced path while the camera moves) where a 3D overview must come at the
    /// cost of a slice, as in `voxhap plan`'s views.
    RenderQuality quality3d = RenderQuality::Full;
    bool shade3d = true;       ///< View3dStyle::shade
    bool linesOnTop3d = false; ///< View3dStyle::linesOnTop
};

class Snapshot {
public:
    /// @brief Copy what the requested views need to VTK (labels only when a
    /// slice shows them or the 3D view draws critical surfaces).
    /// @throw ValueError on an empty view list or a volume without image values
    Snapshot(const volume::Volume& v, const RenderRequest& request, const volume::TissueTable& table);
    ~Snapshot();
    Snapshot(const Snapshot&) = delete;
    Snapshot& operator=(const Snapshot&) = delete;

    const std::vector<ViewKind>& views() const { return mRequest.views; }
    /// @brief The slice position and crosshair actually used [mm, LPS].
    const Vec3d& point() const { return mPoint; }
    const RenderVolume& volume() const { return *mVolume; }
    /// @brief The pixel frame of a requested view.
    const ViewFrame& frame(ViewKind v) const;

    /// @brief Render one requested view. Slices need no display; the 3D view
    /// needs one (DisplayGuard) and keeps its pipeline, so that a second call
    /// measures a steady frame. @throw ValueError for a view not requested or
    /// a 3D view without a display
    Image render(ViewKind v);

private:
    RenderRequest mRequest;
    const volume::TissueTable& mTable;
    std::unique_ptr<RenderVolume> mVolume;
    Vec3d mPoint{0, 0, 0};
    std::vector<std::pair<ViewKind, ViewFrame>> mFrames;
    struct View3d;
    std::unique_ptr<View3d> m3d;
};

/// @brief The views side by side, two to a row in the order given (axial,
/// sagittal / coronal, 3d for the four), each centred in an equal cell.
Image contactSheet(const std::vector<Image>& views);

} // namespace voxhap::render
