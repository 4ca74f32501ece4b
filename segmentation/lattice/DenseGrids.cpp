// SPDX-License-Identifier: Apache-2.0
/// @file DenseGrids.cpp
/// @brief copyToDense / copyFromDense over the segmentation lattice.

#include "segmentation/lattice/DenseGrids.h"

#include <openvdb/tools/Dense.h>
#include <openvdb/tools/Prune.h>

namespace voxhap::segmentation {

namespace {

openvdb::CoordBBox boxOf(const Lattice& lat)
{
    const Vec3i max = lat.origin + lat.dims - Vec3i::Ones();
    return {volume::toCoord(lat.origin), volume::toCoord(max)};
}

template <class T, class GridT> std::vector<T> readDense(const Lattice& lat, const GridT& grid)
{
    std::vector<T> out(lat.size());
    if (out.empty()) return out;
    openvdb::tools::Dense<T, openvdb::tools::LayoutXYZ> dense(boxOf(lat), out.data());
    openvdb::tools::copyToDense(grid, dense, /*serial=*/false);
    return out;
}

template <class GridT, class T>
typename GridT::Ptr writeDense(const Lattice& lat, const std::vector<T>& values, T background)
{
    auto grid = GridT::create(background);
    if (values.empty()) return grid;
    // copyFromDense reads through a const view; the array is not modified.
    openvdb::tools::Dense<T, openvdb::tools::LayoutXYZ> dense(boxOf(lat), const_cast<T*>(values.data()));
    openvdb::tools::copyFromDense(dense, *grid, T(0), /*serial=*/false);
    openvdb::tools::prune(grid->tree()); // uniform regions (deep interiors, bands' far side) as tiles
    return grid;
}

} // namespace

std::vector<float> toDense(const Lattice& lat, const volume::FloatGrid& grid) { return readDense<float>(lat, grid); }
std::vector<std::int32_t> toDense(const Lattice& lat, const volume::LabelGrid& grid)
{
    return readDense<std::int32_t>(lat, grid);
}

volume::LabelGrid::Ptr labelGridFrom(const Lattice& lat, const std::vector<std::int32_t>& ids)
{
    return writeDense<volume::LabelGrid>(lat, ids, volume::kAirLabel);
}

volume::FloatGrid::Ptr floatGridFrom(const Lattice& lat, const std::vector<float>& values, float background)
{
    return writeDense<volume::FloatGrid>(lat, values, background);
}

} // namespace voxhap::segmentation
