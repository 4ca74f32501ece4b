// SPDX-License-Identifier: Apache-2.0
/// @file DenseGrids.h
/// @brief Sparse grids in and out of the dense working arrays, through
/// openvdb::tools::copyToDense / copyFromDense (threaded, layout i-fastest).
#pragma once

#include "segmentation/lattice/Lattice.h"
#include "volume/Grids.h"

#include <cstdint>
#include <vector>

namespace voxhap::segmentation {

/// @brief The values of @p grid over @p lat (inactive voxels read as the background).
std::vector<float> toDense(const Lattice& lat, const volume::FloatGrid& grid);
/// @brief The labels of @p grid over @p lat.
std::vector<std::int32_t> toDense(const Lattice& lat, const volume::LabelGrid& grid);

/// @brief A label grid from dense ids: 0 (air) inactive, uniform regions as tiles.
volume::LabelGrid::Ptr labelGridFrom(const Lattice& lat, const std::vector<std::int32_t>& ids);
/// @brief A float grid with background @p background: values equal to it stay inactive.
volume::FloatGrid::Ptr floatGridFrom(const Lattice& lat, const std::vector<float>& values, float background);

} // namespace voxhap::segmentation
