// SPDX-License-Identifier: Apache-2.0
/// @file SparseSlabs.cpp
/// @brief Slab-wise dense-to-sparse copy with air deactivation.

#include "volume/detail/SparseSlabs.h"

#include "core/Errors.h"
#include "volume/Grids.h"

#include <openvdb/tools/Prune.h>

#include <tbb/parallel_for.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

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

namespace {

// The mask is written a byte at a time (addSlabRows): byte x·8 + y of a leaf's
// 64-bit mask words holds bits x·64 + y·8 .. + 7 only on a little-endian host.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "leaf masks are written as bytes");

using LeafT = FloatGrid::TreeType::LeafNodeType;
constexpr int kDim = int(LeafT::DIM);

/// One 8 x 8 block of a slab's image row: in[z] holds 8 floats (x = 0..7)
/// of slice z; out[x * 8 + z] receives them, which is a leaf's own order for
/// fixed y (LeafNode offsets: x slowest, z fastest). The transposition is
/// what lets the leaf be written in runs of 8 contiguous values instead of
/// one scattered store per voxel.
inline void transpose8(const float* const in[kDim], float out[kDim * kDim])
{
#if defined(__SSE2__)
    for (int zh = 0; zh < 2; ++zh) {
        for (int xh = 0; xh < 2; ++xh) {
            __m128 r0 = _mm_loadu_ps(in[4 * zh + 0] + 4 * xh), r1 = _mm_loadu_ps(in[4 * zh + 1] + 4 * xh);
            __m128 r2 = _mm_loadu_ps(in[4 * zh + 2] + 4 * xh), r3 = _mm_loadu_ps(in[4 * zh + 3] + 4 * xh);
            _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
            float* o = out + 4 * xh * kDim + 4 * zh;
            _mm_storeu_ps(o, r0);
            _mm_storeu_ps(o + kDim, r1);
            _mm_storeu_ps(o + 2 * kDim, r2);
            _mm_storeu_ps(o + 3 * kDim, r3);
        }
    }
#else
    for (int z = 0; z < kDim; ++z)
        for (int x = 0; x < kDim; ++x) out[x * kDim + z] = in[z][x];
#endif
}

/// Bit z set where @p v[z] is not below @p air (a NaN counts as not below,
/// as `v < air` is false for it: the caller has refused NaNs before).
inline unsigned notBelow(const float* v, float air)
{
#if defined(__SSE2__)
    const __m128 a = _mm_set1_ps(air);
    return unsigned(_mm_movemask_ps(_mm_cmpnlt_ps(_mm_loadu_ps(v), a))) |
        unsigned(_mm_movemask_ps(_mm_cmpnlt_ps(_mm_loadu_ps(v + 4), a))) << 4;
#else
    unsigned bits = 0;
    for (int z = 0; z < kDim; ++z) bits |= unsigned(!(v[z] < air)) << z;
    return bits;
#endif
}

/// out[z] = in[z] where bit z of @p bits is set, else @p bg, for z = 0..7.
inline void storeRun(float* out, const float* in, unsigned bits, float bg)
{
#if defined(__SSE2__)
    const __m128i lane = _mm_set_epi32(8, 4, 2, 1);
    const __m128 b = _mm_set1_ps(bg);
    for (int h = 0; h < 2; ++h) {
        const __m128i set = _mm_set1_epi32(int(bits >> (4 * h)));
        const __m128 on = _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_and_si128(set, lane), lane));
        const __m128 v = _mm_loadu_ps(in + 4 * h);
        _mm_storeu_ps(out + 4 * h, _mm_or_ps(_mm_and_ps(on, v), _mm_andnot_ps(on, b)));
    }
#else
    for (int z = 0; z < kDim; ++z) out[z] = (bits >> z) & 1u ? in[z] : bg;
#endif
}

} // namespace

namespace {

/// The slab builder behind addSlabRows and addSlabBlocks: slices k0 .. k0 +
/// nz - 1, one slab (8 slices, a layer of leaves) after another. Per task (one
/// row of 8 x 8 column blocks of one slab): @p Scratch holds what the task's
/// rows need; prepare(scratch, slab, y0, y1) runs once, row(scratch, z, y)
/// gives image row y of slice z of that slab as nx floats. All slabs' tasks
/// form one parallel loop: no core waits for the others at each slab's end,
/// which on busy cores (a worker descheduled mid-task) costs a whole time slice.
template <typename Scratch, typename Prepare, typename Row>
void buildSlab(
    FloatGrid& grid, float air, float bg, Prepare prepare, Row row, int nx, int ny, int k0, int nz, bool finite)
{
    static_assert(SparseSlabs::kSlabSlices == kDim, "a slab is one layer of leaves");
    const int bx = (nx + kDim - 1) / kDim, by = (ny + kDim - 1) / kDim;
    const int slabs = (nz + kDim - 1) / kDim;
    // One leaf per 8 x 8 column block of the slab, built straight from the
    // dense values (exact, no tolerance); all-air blocks make no leaf. This
    // avoids copyFromDense's probing of the growing tree and its whole-tree
    // prune after every slab. Each task takes one row of blocks; for each of
    // its 8 image rows it takes that row of every slice, and each 8 x 8
    // (slice x column) block of those becomes 8 runs of a leaf's values
    // (transpose8) and one byte of its mask per column.
    std::vector<LeafT*> leaves(std::size_t(slabs) * std::size_t(bx) * std::size_t(by), nullptr);
    try {
        tbb::parallel_for(0, slabs * by, [&](int task) {
            const int slab = task / by, yb = task % by;
            const int y0 = yb * kDim;
            const int k0s = k0 + slab * kDim, nzs = std::min(kDim, nz - slab * kDim);
            const unsigned zValid = (1u << nzs) - 1; // slices beyond the last stay inactive background
            const auto fail = [&](int x, int y, int z) {
                throw ValueError("voxel (" + std::to_string(x) + ", " + std::to_string(y) + ", " +
                    std::to_string(k0s + z) + ") is not a finite number");
            };
            LeafT** blockLeaves = leaves.data() + std::size_t(task) * std::size_t(bx);
            // Each leaf's buffer and mask, fetched once (every buffer access checks delayed loading).
            std::vector<float*> values(std::size_t(bx), nullptr);
            std::vector<std::uint8_t*> masks(std::size_t(bx), nullptr);
            // Kept per thread across tasks and slabs: a fresh 128 KiB block per
            // task would be mapped and page-faulted anew each time. Nothing a
            // task calls runs TBB work, so no other task can take it over midway.
            static thread_local Scratch scratch;
            prepare(scratch, slab, y0, std::min(y0 + kDim, ny));
            const float* in[kDim];
            const float* block[kDim];
            float edge[kDim][kDim] = {};           // the last, partial column block, padded
            static const float kUnused[kDim] = {}; // slices past the slab's end: read, then masked out
            alignas(16) float t[kDim * kDim];
            for (int y = y0; y < std::min(y0 + kDim, ny); ++y) {
                const int yy = y - y0;
                for (int z = 0; z < nzs; ++z) {
                    in[z] = row(scratch, z, y);
                    if (finite) continue;
                    // One pass proves the row finite, so that the block loop below
                    // has only one test: air or not.
                    int ok = 1;
                    for (int x = 0; x < nx; ++x) ok &= int(std::abs(in[z][x]) <= std::numeric_limits<float>::max());
                    if (!ok) {
                        for (int x = 0; x < nx; ++x) {
                            if (!(std::abs(in[z][x]) <= std::numeric_limits<float>::max())) fail(x, y, z); // NaN, ±inf
                        }
                    }
                }
                for (int b = 0; b < bx; ++b) {
                    const int x0 = b * kDim, w = std::min(kDim, nx - x0);
                    for (int z = 0; z < kDim; ++z) {
                        if (z >= nzs) {
                            block[z] = kUnused;
                        } else if (w == kDim) {
                            block[z] = in[z] + x0;
                        } else { // never read past a row's end: the row may be the caller's own data
                            std::copy(in[z] + x0, in[z] + x0 + w, edge[z]);
                            block[z] = edge[z];
                        }
                    }
                    transpose8(block, t);
                    unsigned bits[kDim], any = 0;
                    for (int xx = 0; xx < w; ++xx) any |= bits[xx] = notBelow(t + xx * kDim, air) & zValid;
                    if (!any) continue; // air: the inactive background, no leaf needed for it
                    if (!blockLeaves[b]) {
                        blockLeaves[b] = new LeafT(openvdb::Coord(x0, y0, k0s), bg, false);
                        values[std::size_t(b)] = blockLeaves[b]->buffer().data();
                        masks[std::size_t(b)] = &blockLeaves[b]->getValueMask().template getWord<std::uint8_t>(0);
                    }
                    float* v = values[std::size_t(b)];
                    std::uint8_t* m = masks[std::size_t(b)];
                    for (int xx = 0; xx < w; ++xx) {
                        if (!bits[xx]) continue;
                        // Offset x·64 + y·8 + z: the 8 slices of (x, y) are contiguous, and
                        // their mask bits are byte x·8 + y of the (little-endian) mask.
                        storeRun(v + (xx << 6) + (yy << 3), t + xx * kDim, bits[xx], bg);
                        m[(xx << 3) + yy] = std::uint8_t(bits[xx]);
                    }
                }
            }
        });
    } catch (...) {
        for (LeafT* l : leaves) delete l;
        throw;
    }
    auto& tree = grid.tree();
    for (LeafT* l : leaves) {
        if (l) tree.addLeaf(l); // the tree takes ownership
    }
}

} // namespace

void SparseSlabs::addSlabRows(const RowSource& rows, int nx, int ny, int k0, int nz, bool finite)
{
    if (k0 % kDim != 0 || nz < 1 || nz > kDim)
        throw ValueError("slab at k = " + std::to_string(k0) + " is not leaf-aligned");
    using Scratch = std::vector<float>; // one row of each slice, for sources that convert into it
    buildSlab<Scratch>(
        *mImpl->grid, mImpl->airBelow, mImpl->background,
        [nx](Scratch& s, int, int, int) { s.resize(std::size_t(nx) * kDim); },
        [&rows, nx](Scratch& s, int z, int y) { return rows(z, y, s.data() + std::size_t(z) * std::size_t(nx)); }, nx,
        ny, k0, nz, finite);
}

void SparseSlabs::addSlabBlocks(const BlockSource& blocks, int nx, int ny, int k0, int nz, bool finite)
{
    if (k0 % kDim != 0 || nz < 1) throw ValueError("slab at k = " + std::to_string(k0) + " is not leaf-aligned");
    struct Scratch {
        std::vector<float> rows; ///< rows y0 .. y0 + 7 of every slice: slice-major, then row
        int y0 = 0;
    };
    buildSlab<Scratch>(
        *mImpl->grid, mImpl->airBelow, mImpl->background,
        [&blocks, nx, nz](Scratch& s, int slab, int y0, int y1) {
            s.rows.resize(std::size_t(nx) * kDim * kDim);
            s.y0 = y0;
            const int z0 = slab * kDim, n = std::min(kDim, nz - z0);
            for (int z = 0; z < n; ++z) {
                blocks(z0 + z, y0, y1, s.rows.data() + std::size_t(z) * kDim * std::size_t(nx));
            }
        },
        [nx](Scratch& s, int z, int y) -> const float* {
            return s.rows.data() + (std::size_t(z) * kDim + std::size_t(y - s.y0)) * std::size_t(nx);
        },
        nx, ny, k0, nz, finite);
}

Volume::GridPtr SparseSlabs::finish()
{
    openvdb::tools::pruneInactive(mImpl->grid->tree());
    Volume::GridPtr out = mImpl->grid;
    mImpl->grid = FloatGrid::create(mImpl->background);
    return out;
}

} // namespace voxhap::volume
