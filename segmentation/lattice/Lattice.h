// SPDX-License-Identifier: Apache-2.0
/// @file Lattice.h
/// @brief Dense working arrays over a volume's index box, for segmentation.
///
/// Segmentation runs on dense arrays, not on the sparse grids: it needs
/// Euclidean distances in millimetres on anisotropic voxels (the real CT has
/// 1.07 × 1.07 × 3 mm voxels), which OpenVDB's dilate/erode cannot give — they
/// are index-space stencils, so one step is 1 mm in-plane but 3 mm between
/// slices — and it visits every voxel of the box several times, where a flat
/// array with strides is the fastest layout there is. The sparse grids are
/// read once into these arrays and the labels written back once
/// (segmentation/lattice/DenseGrids.h).
#pragma once

#include "core/Math.h"
#include "volume/Volume.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace voxhap::segmentation {

using voxhap::Vec3d;
using voxhap::Vec3i;

/// @brief The box's voxels in memory order: i fastest, then j, then k.
struct Lattice {
    Vec3i dims{0, 0, 0};          ///< voxels along i, j, k
    Vec3d spacing{1.0, 1.0, 1.0}; ///< voxel size along i, j, k [mm]
    Vec3i origin{0, 0, 0};        ///< index coordinate of element 0 (the box's min corner)
    int sliceAxis = 2;            ///< the index axis closest to the patient's cranio-caudal axis

    /// @brief The lattice of @p v's index box; the slice axis from its direction cosines.
    static Lattice of(const volume::Volume& v);

    std::size_t size() const { return std::size_t(dims.x()) * std::size_t(dims.y()) * std::size_t(dims.z()); }
    std::array<std::size_t, 3> strides() const
    {
        return {1, std::size_t(dims.x()), std::size_t(dims.x()) * std::size_t(dims.y())};
    }
    std::size_t index(int i, int j, int k) const
    {
        return std::size_t(i) + std::size_t(dims.x()) * (std::size_t(j) + std::size_t(dims.y()) * std::size_t(k));
    }
    /// @brief Lattice position (i, j, k from 0) of element @p n.
    Vec3i position(std::size_t n) const
    {
        const std::size_t nx = std::size_t(dims.x()), ny = std::size_t(dims.y());
        return {int(n % nx), int((n / nx) % ny), int(n / (nx * ny))};
    }
    /// @brief Volume of one voxel [ml].
    double voxelMl() const { return spacing.prod() * 1e-3; }
    /// @brief The two in-plane axes (the axes other than the slice axis).
    std::array<int, 2> planeAxes() const { return {sliceAxis == 0 ? 1 : 0, sliceAxis == 2 ? 1 : 2}; }
};

/// @brief A binary mask over a lattice: 1 in, 0 out.
using Mask = std::vector<std::uint8_t>;

/// @brief Which axes an operation spans: all three, or the two in-plane axes (per slice).
enum class Span {
    Volume,
    Slice
};

} // namespace voxhap::segmentation
