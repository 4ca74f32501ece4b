// SPDX-License-Identifier: Apache-2.0
/// @file SparseSlabs.cpp
/// @brief Slab-wise dense-to-sparse copy with air deactivation.

#include "volume/SparseSlabs.h"

#include "volume/Errors.h"
#include "volume/Grids.h"

#include <openvdb/tools/Prune.h>

#include <tbb/parallel_for.h>

#include <cmath>
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
    using LeafT = FloatGrid::TreeType::LeafNodeType;
    constexpr int kDim = int(LeafT::DIM);
    static_assert(kSlabSlices == kDim, "a slab is one layer of leaves");
    if (k0 % kDim != 0 || nz < 1 || nz > kDim) throw ValueError("slab at k = " + std::to_string(k0) + " is not leaf-aligned");
    const float air = mImpl->airBelow, bg = mImpl->background;
    const int bx = (nx + kDim - 1) / kDim, by = (ny + kDim - 1) / kDim;
    const std::size_t plane = std::size_t(nx) * std::size_t(ny);
    // One leaf per 8 × 8 column block of the slab, built in parallel straight
    // from the dense values (exact, no tolerance); all-air blocks make no leaf.
    // This avoids copyFromDense's probing of the growing tree and its
    // whole-tree prune after every slab.
    std::vector<LeafT*> leaves(std::size_t(bx) * std::size_t(by), nullptr);
    try {
        tbb::parallel_for(0, bx * by, [&](int b) {
            const int x0 = (b % bx) * kDim, y0 = (b / bx) * kDim;
            std::unique_ptr<LeafT> leaf;
            float* values = nullptr; // the leaf's buffer, fetched once (each access checks delayed loading)
            for (int z = 0; z < nz; ++z) {
                for (int y = y0; y < std::min(y0 + kDim, ny); ++y) {
                    const float* row = data + plane * std::size_t(z) + std::size_t(y) * std::size_t(nx);
                    for (int x = x0; x < std::min(x0 + kDim, nx); ++x) {
                        const float v = row[x];
                        if (!std::isfinite(v)) {
                            throw ValueError("voxel (" + std::to_string(x) + ", " + std::to_string(y) + ", " +
                                             std::to_string(k0 + z) + ") is not a finite number");
                        }
                        if (v < air) continue; // air: the inactive background
                        if (!leaf) {
                            leaf = std::make_unique<LeafT>(openvdb::Coord(x0, y0, k0), bg, false);
                            values = leaf->buffer().data();
                        }
                        // LeafNode offsets: x slowest, z fastest, within the 8³ block.
                        const openvdb::Index n = openvdb::Index(((x - x0) << 6) | ((y - y0) << 3) | z);
                        values[n] = v;
                        leaf->getValueMask().setOn(n);
                    }
                }
            }
            leaves[std::size_t(b)] = leaf.release();
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
