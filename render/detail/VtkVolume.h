// SPDX-License-Identifier: Apache-2.0
/// @file VtkVolume.h
/// @brief The VTK arrays behind a RenderVolume. Included only by render/'s
/// VTK translation units (RenderVolume.cpp, VolumeView3d.cpp, Viewer.cpp).
#pragma once

#include "render/views/RenderVolume.h"

#include <vtkImageData.h>
#include <vtkMatrix4x4.h>
#include <vtkSmartPointer.h>

#include <array>

namespace voxhap::render {

struct RenderVolume::Impl {
    ScalarChannel channel = ScalarChannel::Hu;
    /// Image values (float). Point data on the volume's index lattice: extent =
    /// the index box, spacing = voxel size, origin 0, so that a point's data
    /// coordinate is spacing ⊙ ijk and world = origin + direction · data.
    vtkSmartPointer<vtkImageData> scalars;
    vtkSmartPointer<vtkImageData> labels; ///< tissue ids (short), or null
    Mat3d direction = Mat3d::Identity();  ///< columns: world directions of i, j, k
    Vec3d origin{0, 0, 0};                ///< world position of index (0, 0, 0) [mm]
    Vec3d spacing{1, 1, 1};               ///< [mm]
    WorldBounds bounds;
    double background = 0.0, lo = 0.0, hi = 0.0, tissueMean = 0.0;
    std::array<double, 2> bodyRange{0.0, 0.0}; ///< RenderVolume::bodyRange()

    /// @brief World ← data coordinates: the matrix a vtkProp3D showing these arrays needs.
    vtkSmartPointer<vtkMatrix4x4> dataToWorld() const;
};

} // namespace voxhap::render
