// SPDX-License-Identifier: Apache-2.0
/// @file SparseSlabs.h
/// @brief Build a sparse float grid from a dense volume delivered slab by slab
/// (a few slices at a time), so that the dense volume never exists whole.
///
/// Values are copied exactly (tolerance 0: a tolerance would collapse soft
/// tissue into constant tiles); voxels below the air threshold become the
/// inactive background. Memory stays at the sparse result plus one slab.
#pragma once

#include "volume/Volume.h"

#include <cstdint>
#include <functional>
#include <memory>

namespace voxhap::volume {

/// @brief Collects z-slabs of a dense array (x fastest, then y, then z) into a
/// FloatGrid whose background is @p background.
/// @note Not thread-safe; addSlab itself runs in parallel (TBB).
class SparseSlabs {
public:
    /// @param background the inactive value (kAirHu or kAirT1)
    /// @param airBelow   values below this become inactive background (air)
    SparseSlabs(float background, float airBelow);
    ~SparseSlabs();
    SparseSlabs(const SparseSlabs&) = delete;
    SparseSlabs& operator=(const SparseSlabs&) = delete;

    /// @brief Slab thickness in slices that keeps slabs aligned with OpenVDB leaves.
    static constexpr int kSlabSlices = 8;

    /// @brief Add slices k0 .. k0+nz-1 of an nx × ny image stack.
    /// @param data nx·ny·nz values, x fastest (read only)
    /// @param k0   a multiple of kSlabSlices; nz at most kSlabSlices; each slab added once
    /// @throw ValueError on a non-finite value (naming its index) or a misaligned slab
    void addSlab(float* data, int nx, int ny, int k0, int nz);

    /// @brief Image row @p y of slab slice @p z as nx floats: either a pointer
    /// into data the caller holds, or @p scratch (nx floats) filled.
    using RowSource = std::function<const float*(int z, int y, float* scratch)>;

    /// @brief As addSlab, with each row produced on demand (by any thread):
    /// a loader converts stored samples straight into the leaves, and the
    /// slab of floats never exists.
    /// @param finite the rows are known finite (integer samples under a finite
    ///               rescale): the per-row finiteness pass is skipped
    void addSlabRows(const RowSource& rows, int nx, int ny, int k0, int nz, bool finite = false);

    /// @brief Rows y0 .. y1 - 1 of slab slice @p z as floats, nx per row, row
    /// after row, into @p out (called by any thread, once per slice and row of
    /// leaves).
    using BlockSource = std::function<void(int z, int y0, int y1, float* out)>;

    /// @brief As addSlabRows, with the rows of one row of leaves (8 image rows
    /// of every slice of a slab) produced together: a loader reads those rows
    /// straight from each file and converts them while they are in the cache,
    /// and neither a slab's stored samples nor its floats ever exist whole.
    /// Slices k0 .. k0 + nz - 1, any number of slabs (nz may exceed
    /// kSlabSlices; @p blocks then sees z from 0 to nz - 1), in one parallel loop.
    void addSlabBlocks(const BlockSource& blocks, int nx, int ny, int k0, int nz, bool finite = false);

    /// @brief The grid built so far (the builder is empty afterwards).
    Volume::GridPtr finish();

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace voxhap::volume
