// SPDX-License-Identifier: Apache-2.0
/// @file VolumeView3d.h
/// @brief The 3D view: the volume ray-cast by VTK in one of the four blend
/// modes, critical structures as surfaces from the label map, planned paths and
/// the needle as 3D lines, seen as a parallel projection from the front.
///
/// Needs an X display (Display.h); the constructor checks for one and throws
/// rather than let VTK abort the process.
#pragma once

#include "render/raster/Image.h"
#include "render/views/Overlays.h"
#include "render/views/ViewFrame.h"
#include "render/views/ViewTypes.h"

#include <cstddef>
#include <memory>

namespace voxhap::volume {
class TissueTable;
}

namespace voxhap::render {

class RenderVolume;

/// @brief Which VTK ray caster draws the volume.
enum class RayCaster {
    Auto, ///< the faster one for the mode (measured by bench_render): CPU, except GPU for the sum
    Gpu,  ///< vtkGPUVolumeRayCastMapper (Mesa llvmpipe under Xvfb): all four modes
    Cpu,  ///< vtkFixedPointVolumeRayCastMapper (multi-threaded): composite and MIP only
};

/// @brief What the 3D view draws while the camera moves (measured by `voxhap bench render`).
enum class MovingPath {
    Subsample, ///< the same ray caster, one ray per movingFactor² pixels, steps movingFactor× longer, nearest voxel
    Shrunk,    ///< a second ray caster on a copy averaged over movingFactor voxels per side (vtkImageShrink3D)
    AutoRate,  ///< the same ray caster left to meet 10 frames/s itself (VTK's AutoAdjustSampleDistances)
};

/// @brief The quality of one 3D frame.
enum class RenderQuality {
    Full,   ///< one ray per pixel, steps of sampleVoxels, trilinear: the still picture
    Moving, ///< the View3dStyle's moving path, and the critical surfaces from the label map sampled
            ///< at the moving ray step, opaque: for frames while the camera moves
};

struct View3dStyle {
    BlendMode mode = BlendMode::Colour;
    RayCaster caster = RayCaster::Auto;
    WindowLevel window;                        ///< grey ramp of the grey and MIP modes, and of MR's colour mode
    bool criticalSurfaces = true;              ///< surfaces of the table's critical tissues (needs labels)
    double sampleVoxels = 1.0;                 ///< ray step in units of the finest voxel size
    MovingPath moving = MovingPath::Subsample; ///< how RenderQuality::Moving frames are drawn
    int movingFactor = 3;                      ///< the moving path's reduction per side (Subsample, Shrunk)
    /// Gradient shading of the colour and grey modes. Off spares the mapper its
    /// per-voxel normals (a second of CPU on a CT) where a quick overview is enough.
    bool shade = true;
    /// Paths, entries, targets and the needle drawn on a layer above the volume
    /// in every mode, not only in the projections: an overview whose subject is
    /// the path (`voxhap plan`'s fourth quadrant) must show it even where the
    /// body lies in front of it. Off, composite modes hide what lies behind tissue.
    bool linesOnTop = false;
};

class VolumeView3d {
public:
    /// @param frame     the image plane (ViewKind::ThreeD): the camera looks along its normal
    /// @param overlays  paths, needle (as 3D lines) and the annotations
    /// @throw ValueError if no X display is reachable
    VolumeView3d(const RenderVolume& v, const ViewFrame& frame, const View3dStyle& style,
        const volume::TissueTable& table, const Overlays& overlays);
    ~VolumeView3d();
    VolumeView3d(const VolumeView3d&) = delete;
    VolumeView3d& operator=(const VolumeView3d&) = delete;

    /// @brief Render one frame and read it back (the first frame of a quality also
    /// builds that path's tables: gradients, shaders).
    Image render(RenderQuality quality = RenderQuality::Full);
    /// @brief The quality of the last render().
    RenderQuality lastQuality() const;
    /// @brief Triangles of the critical surfaces in the last render() (0 without
    /// them): moving frames draw them from the label map sampled at the moving
    /// ray step (movingFactor full steps), so about (that step in voxels)² fewer.
    std::size_t criticalTriangles() const;
    /// @brief Point the camera along another frame of the same size in pixels
    /// (OrbitCamera.h): a parallel projection whose pixel (x, y) shows the ray
    /// through frame.toWorld(x, y). The orientation letters follow it.
    void setCamera(const ViewFrame& frame);
    /// @brief The ray caster in use (Auto resolved).
    RayCaster caster() const;
    /// @brief Move (or remove) the live needle drawn in the view.
    void setNeedle(const std::optional<planning::NeedlePose>& needle);

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace voxhap::render
