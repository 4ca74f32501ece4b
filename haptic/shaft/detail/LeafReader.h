// SPDX-License-Identifier: Apache-2.0
/// @file LeafReader.h
/// @brief Voxel reads along a path with the current leaf cached: a read in the
/// same 8³ block is an index into the leaf's buffer (toolchain.md measured the
/// leaf-local path at about half the cost of a sampler with a cached accessor).
#pragma once

#include <openvdb/openvdb.h>

#include <limits>

namespace voxhap::haptic::detail {

/// @brief Reads values of one tree, remembering the last leaf (or tile) touched.
/// @warning Not thread-safe: one per thread. Owns its accessor (style.md §2).
template <typename TreeT> class LeafReader {
public:
    using LeafT = typename TreeT::LeafNodeType;
    using ValueT = typename TreeT::ValueType;
    static constexpr int kMask = ~int(LeafT::DIM - 1);

    explicit LeafReader(const TreeT& tree) : mAcc(tree) { }
    LeafReader(const LeafReader& o) : mAcc(o.mAcc.tree()) { }
    LeafReader& operator=(const LeafReader&) = delete;

    /// @brief The value at @p c (active or not), as the tree stores it.
    ValueT get(const openvdb::Coord& c) noexcept
    {
        touch(c);
        return mData ? mData[LeafT::coordToOffset(c)] : mConstant;
    }

    /// @brief If @p c lies in a uniform region (a tile, or background), the side
    /// of the aligned cube of voxels that shares its value (8, 128 or 4096); 0 in a leaf.
    int uniformBlock(const openvdb::Coord& c) noexcept
    {
        touch(c);
        return mData ? 0 : mBlockDim;
    }

    /// @brief The buffer of the leaf holding @p c, or nullptr in a uniform region.
    const ValueT* leafData(const openvdb::Coord& c) noexcept
    {
        touch(c);
        return mData;
    }

private:
    void touch(const openvdb::Coord& c) noexcept
    {
        const openvdb::Coord o(c.x() & kMask, c.y() & kMask, c.z() & kMask);
        if (o != mOrigin) refill(o);
    }

    void refill(const openvdb::Coord& o) noexcept
    {
        mOrigin = o;
        if (const LeafT* leaf = mAcc.probeConstLeaf(o)) {
            mData = leaf->buffer().data();
        } else { // a tile or the background: one value for the whole block
            mData = nullptr;
            mConstant = mAcc.getValue(o);
            // Depth at which the value lives: 0 root tile (4096³), 1 upper internal
            // tile (128³), 2 lower internal tile (8³); -1 background, i.e. no root
            // child, whose aligned 4096³ block is all background.
            switch (mAcc.getValueDepth(o)) {
            case 1:
                mBlockDim = 128;
                break;
            case 2:
                mBlockDim = int(LeafT::DIM);
                break;
            default:
                mBlockDim = 4096;
                break;
            }
        }
    }

    openvdb::tree::ValueAccessor<const TreeT> mAcc;
    openvdb::Coord mOrigin{std::numeric_limits<int>::max()};
    const ValueT* mData = nullptr;
    ValueT mConstant{};
    int mBlockDim = 0;
};

} // namespace voxhap::haptic::detail
