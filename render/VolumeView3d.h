// SPDX-License-Identifier: Apache-2.0
/// @file VolumeView3d.h
/// @brief The 3D view: the volume ray-cast by VTK in one of the four blend
/// modes, critical structures as surfaces from the label map, planned paths and
/// the needle as 3D lines, seen as a parallel projection from the front.
///
/// Needs an X display (Display.h); the constructor checks for one and throws
/// rather than let VTK abort the process.
#pragma once

#include "render/Image.h"
#include "render/Overlays.h"
#include "render/ViewFrame.h"
#include "render/ViewTypes.h"

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

struct View3dStyle {
    BlendMode mode = BlendMode::Colour;
    RayCaster caster = RayCaster::Auto;
    WindowLevel window;           ///< grey ramp of the grey and MIP modes, and of MR's colour mode
    bool criticalSurfaces = true; ///< surfaces of the table's critical tissues (needs labels)
    double sampleVoxels = 1.0;    ///< ray step in units of the finest voxel size
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

    /// @brief Render one frame and read it back (the first frame also compiles the shaders).
    Image render();
    /// @brief The ray caster in use (Auto resolved).
    RayCaster caster() const;
    /// @brief Move (or remove) the live needle drawn in the view.
    void setNeedle(const std::optional<NeedlePose>& needle);

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace voxhap::render
