// SPDX-License-Identifier: Apache-2.0
/// @file RenderVolume.h
/// @brief A patient volume handed to VTK once: one dense copy of its image
/// grid (hu, else t1) and, only when a view needs them, of its tissue labels.
/// Every slice and the 3D view read these same arrays; no view copies them.
///
/// The dense arrays keep the volume's index lattice (spacing and direction
/// cosines, oblique or anisotropic): slices are resampled from it onto LPS
/// planes, and the 3D view places it in the world with a matrix.
#pragma once

#include "render/ViewFrame.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace voxhap::volume {
class Volume;
}

namespace voxhap::render {

/// @brief Which grid the views show.
enum class ScalarChannel { Hu, T1 };

class RenderVolume {
public:
    /// @param withLabels also copy the label grid (ignored if the volume has none)
    /// @throw ValueError if the volume has neither a hu nor a t1 grid, or is empty
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
