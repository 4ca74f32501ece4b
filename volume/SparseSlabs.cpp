// SPDX-License-Identifier: Apache-2.0
/// @file SparseSlabs.cpp
/// @brief Slab-wise dense-to-sparse copy with air deactivation.

#include "volume/SparseSlabs.h"

#include "volume/Errors.h"
#include "volume/Grids.h"

#include <openvdb/tools/Dense.h>
#include <openvdb/tools/Prune.h>

#include <tbb/parallel_for.h>

#include <cmath>
#include <string>

namespace voxhap::volume {

struct SparseSlabs::Impl {
    float background;
    float airBelow;
    FloatGrid::Ptr grid;
};

SparseSlabs::SparseSlabs(float background, float airBelow) : mImpl(std::make_unique<Impl>())
{
    initializeOpenVdb();
    mImpl->background = background;
    mImpl->airBelow = airBelow;
    mImpl->grid = FloatGrid::create(background);
}

SparseSlabs::~SparseSlabs() = default;

void SparseSlabs::addSlab(float* data, int nx, int ny, int k0, int nz)
{
    const std::size_t plane = std::size_t(nx) * std::size_t(ny);
    const float air = mImpl->airBelow, bg = mImpl->background;
    // Air becomes exactly the background first, so that copyFromDense (tolerance 0)
    // leaves it inactive and collapses all-air leaves into background tiles.
    tbb::parallel_for(0, nz, [&](int k) {
        float* p = data + plane * std::size_t(k);
        for (std::size_t n = 0; n < plane; ++n) {
            if (!std::isfinite(p[n])) {
                throw ValueError("voxel (" + std::to_string(n % std::size_t(nx)) + ", " +
                                 std::to_string(n / std::size_t(nx)) + ", " + std::to_string(k0 + k) +
                                 ") is not a finite number");
            }
            if (p[n] < air) p[n] = bg;
        }
    });
    const openvdb::CoordBBox box(openvdb::Coord(0, 0, k0), openvdb::Coord(nx - 1, ny - 1, k0 + nz - 1));
    openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> dense(box, data);
    openvdb::tools::copyFromDense(dense, *mImpl->grid, /*tolerance=*/0.0f, /*serial=*/false);
}

Volume::GridPtr SparseSlabs::finish()
{
    openvdb::tools::pruneInactive(mImpl->grid->tree());
    Volume::GridPtr out = mImpl->grid;
    mImpl->grid = FloatGrid::create(mImpl->background);
    return out;
}

} // namespace voxhap::volume
