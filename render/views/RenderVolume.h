// SPDX-License-Identifier: Apache-2.0
/// @file RenderVolume.h
/// @brief A patient volume handed to VTK once: one dense copy of its image
/// grid (hu, else t1, else intensity) and, only when a view needs them, of its
/// tissue labels. Every slice and the 3D view read these same arrays; no view
/// copies them.
///
/// The default window comes from the data. CT numbers mean the same on every
/// scanner, so CT gets the usual presets (ViewTypes.h). MR values do not: a T1
/// map is in ms, any other MR in arbitrary units that differ from scan to scan,
/// so MR gets the range of its own body (the active voxels: the loaders leave
/// air inactive) between robust percentiles, and never a CT preset. The
/// percentiles are VTK's auto-range defaults (vtkImageHistogramStatistics:
/// 1st and 99th, without its 10 % widening), which 3D Slicer's automatic
/// window/level builds on (vtkMRMLScalarVolumeDisplayNode::CalculateAutoLevels,
/// there over every voxel at 0.1 and 99.9 %; its comment notes that empty space
/// around the body pulls such a range down, which counting only the body avoids).
///
/// The dense arrays keep the volume's index lattice (spacing and direction
/// cosines, oblique or anisotropic): slices are resampled from it onto LPS
/// planes, and the 3D view places it in the world with a matrix.
#pragma once

#include "render/views/ViewFrame.h"
#include "render/views/ViewTypes.h"

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace voxhap::volume {
class Volume;
}

namespace voxhap::render {

/// @brief Which grid the views show.
enum class ScalarChannel {
    Hu,        ///< CT [HU]
    T1,        ///< MR T1 [ms]
    Intensity, ///< MR signal that is not T1 [arbitrary units]
};

/// @brief The unit of a channel's values as the views label it: "HU", "ms" or
/// "a.u." (arbitrary units).
std::string_view scalarUnits(ScalarChannel c);

/// @brief A window's legend for the views: the channel, the grey ramp's ends and
/// the unit, e.g. "T1 150..5000 ms", "MR 12..820 a.u.", "CT -160..240 HU".
std::string windowLegend(ScalarChannel c, const WindowLevel& w);

/// @name The body's robust range on MR [percent of the active voxels].
/// @{
inline constexpr double kBodyLowPercentile = 1.0;
inline constexpr double kBodyHighPercentile = 99.0;
/// @}

class RenderVolume {
public:
    /// @param withLabels also copy the label grid (ignored if the volume has none)
    /// @throw ValueError if the volume has no hu, t1 or intensity grid, or is empty
    RenderVolume(const volume::Volume& v, bool withLabels);
    ~RenderVolume();
    RenderVolume(const RenderVolume&) = delete;
    RenderVolume& operator=(const RenderVolume&) = delete;

    ScalarChannel channel() const;
    bool hasLabels() const;
    /// @brief Axis-aligned world box of the voxels, faces included [mm, LPS].
    WorldBounds worldBounds() const;
    /// @brief The smallest voxel size [mm]: the default pixel size of the views.
    double finestSpacing() const;
    /// @brief Smallest and largest image value (the air background included).
    double scalarMin() const;
    double scalarMax() const;
    /// @brief Mean image value of the voxels above the background (what the
    /// summed projection is scaled by).
    double tissueMean() const;
    /// @brief The kBodyLowPercentile and kBodyHighPercentile of the active
    /// voxels' values (the body), to 1/65536 of their range (a histogram); the
    /// value range if no voxel is active. On CT: the value range (unused).
    std::array<double, 2> bodyRange() const;
    /// @brief The window views use unless told otherwise: on CT the soft-tissue
    /// preset (bone for a maximum intensity projection); on MR the body's
    /// robust range whatever the mode (bodyRange()).
    WindowLevel defaultWindow(BlendMode mode = BlendMode::Colour) const;
    /// @brief Bytes of the dense arrays handed to VTK.
    std::size_t denseBytes() const;

    /// @brief The image values on a view's plane, row by row from the top:
    /// trilinear, the air background outside the volume.
    std::vector<float> sliceValues(const ViewFrame& f) const;
    /// @brief The tissue labels on a view's plane (nearest voxel), 0 outside;
    /// empty without labels.
    std::vector<std::int32_t> sliceLabels(const ViewFrame& f) const;

    /// The VTK side (render/detail/VtkVolume.h): for render's own VTK code only.
    struct Impl;
    const Impl& impl() const { return *mImpl; }

private:
    std::unique_ptr<Impl> mImpl;
};

} // namespace voxhap::render
