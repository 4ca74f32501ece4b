// SPDX-License-Identifier: Apache-2.0
/// @file SparseSlabs.cpp
/// @brief Slab-wise dense-to-sparse copy with air deactivation.

#include "volume/detail/SparseSlabs.h"

#include "core/Errors.h"
#include "volume/Grids.h"

#include <openvdb/tools/Prune.h>

#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>
#include <memory>
#include <vector>
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
    addSlabRows([&](int z, int y, float*) { return data + plane * std::size_t(z) + std::size_t(y) * std::size_t(nx); },
        nx, ny, k0, nz, false);
}

void SparseSlabs::addSlabRows(const RowSource& rows, int nx, int ny, int k0, int nz, bool finite)
{
    using LeafT = FloatGrid::TreeType::LeafNodeType;
    constexpr int kDim = int(LeafT::DIM);
    static_assert(kSlabSlices == kDim, "a slab is one layer of leaves");
    if (k0 % kDim != 0 || nz < 1 || nz > kDim)
        throw ValueError("slab at k = " + std::to_string(k0) + " is not leaf-aligned");
    const float air = mImpl->airBelow, bg = mImpl->background;
    const int bx = (nx + kDim - 1) / kDim, by = (ny + kDim - 1) / kDim;
    // One leaf per 8 × 8 column block of the slab, built straight from the
    // dense values (exact, no tolerance); all-air blocks make no leaf. This
    // avoids copyFromDense's probing of the growing tree and its whole-tree
    // prune after every slab. Each task takes one row of blocks and reads its
    // 8 image rows of every slice front to back, so the slab streams through
    // the cache once while the row's leaves (bx × 2 KiB) stay in it.
    std::vector<LeafT*> leaves(std::size_t(bx) * std::size_t(by), nullptr);
    const auto fail = [&](int x, int y, int z) {
        throw ValueError("voxel (" + std::to_string(x) + ", " + std::to_string(y) + ", " + std::to_string(k0 + z) +
            ") is not a finite number");
    };
    try {
        tbb::parallel_for(0, by, [&](int yb) {
            const int y0 = yb * kDim;
            LeafT** row = leaves.data() + std::size_t(yb) * std::size_t(bx);
            // Each leaf's buffer, fetched once (every buffer access checks delayed loading).
            std::vector<float*> values(std::size_t(bx), nullptr);
            std::vector<float> scratch(static_cast<std::size_t>(nx));
            for (int z = 0; z < nz; ++z) {
                for (int y = y0; y < std::min(y0 + kDim, ny); ++y) {
                    const float* in = rows(z, y, scratch.data());
                    // One pass proves the row finite (or the source promised it),
                    // so that the per-voxel loop has one test: air or not.
                    bool rowFinite = finite;
                    if (!rowFinite) {
                        int ok = 1;
                        for (int x = 0; x < nx; ++x) ok &= int(std::abs(in[x]) <= std::numeric_limits<float>::max());
                        rowFinite = ok;
                    }
                    if (!rowFinite) {
                        for (int x = 0; x < nx; ++x) {
                            if (!(std::abs(in[x]) <= std::numeric_limits<float>::max())) fail(x, y, z); // NaN, ±inf
                        }
                    }
                    const float airBelow = air; // a local: the compiler keeps it in a register
                    for (int x = 0; x < nx; ++x) {
                        const float v = in[x];
                        if (v < airBelow) continue; // air: the inactive background
                        const int b = x / kDim;
                        if (!row[b]) {
                            row[b] = new LeafT(openvdb::Coord(x - x % kDim, y0, k0), bg, false);
                            values[std::size_t(b)] = row[b]->buffer().data();
                        }
                        // LeafNode offsets: x slowest, z fastest, within the 8³ block.
                        const openvdb::Index n = openvdb::Index(((x % kDim) << 6) | ((y - y0) << 3) | z);
                        values[std::size_t(b)][n] = v;
                        row[b]->getValueMask().setOn(n);
                    }
                }
            }
        });
    } catch (...) {
        for (LeafT* l : leaves) delete l;
        throw;
    }
    auto& tree = mImpl->grid->tree();
    for (LeafT* l : leaves) {
        if (l) tree.addLeaf(l); // the tree takes ownership
    }
}

Volume::GridPtr SparseSlabs::finish()
{
    openvdb::tools::pruneInactive(mImpl->grid->tree());
    Volume::GridPtr out = mImpl->grid;
    mImpl->grid = FloatGrid::create(mImpl->background);
    return out;
}

} // namespace voxhap::volume
