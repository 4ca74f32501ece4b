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
template <typename TreeT>
class LeafReader {
public:
    using LeafT = typename TreeT::LeafNodeType;
    using ValueT = typename TreeT::ValueType;
    static constexpr int kMask = ~int(LeafT::DIM - 1);

    explicit LeafReader(const TreeT& tree) : mAcc(tree) {}
    LeafReader(const LeafReader& o) : mAcc(o.mAcc.tree()) {}
    LeafReader& operator=(const LeafReader&) = delete;

    /// @brief The value at @p c (active or not), as the tree stores it.
    ValueT get(const openvdb::Coord& c) noexcept
    {
        const openvdb::Coord o(c.x() & kMask, c.y() & kMask, c.z() & kMask);
        if (o != mOrigin) refill(o);
        return mData ? mData[LeafT::coordToOffset(c)] : mConstant;
    }

private:
    void refill(const openvdb::Coord& o) noexcept
    {
        mOrigin = o;
        if (const LeafT* leaf = mAcc.probeConstLeaf(o)) {
            mData = leaf->buffer().data();
        } else { // a tile or the background: one value for the whole block
            mData = nullptr;
            mConstant = mAcc.getValue(o);
        }
    }

    openvdb::tree::ValueAccessor<const TreeT> mAcc;
    openvdb::Coord mOrigin{std::numeric_limits<int>::max()};
    const ValueT* mData = nullptr;
    ValueT mConstant{};
};

} // namespace voxhap::haptic::detail
