// SPDX-License-Identifier: Apache-2.0
/// @file VoxelWalk.h
/// @brief The exact chord pass and its walk: one Amanatides–Woo voxel walk
/// that never restarts inside leaves, reading each 8³ leaf's buffer directly,
/// stepping block by block over runs of 8³ tiles and jumping larger uniform
/// blocks (128³ tiles, background) in one step.
///
/// Why not openvdb::math::DDA with a leaf reader (walkCellsSkipping), or the
/// two-level block DDA a careful OpenVDB user writes (bench/BlockDdaPeer.h):
/// on a real CT nearly every block crossed is a leaf, and both pay at every
/// leaf for a voxel DDA started afresh and a tree query. Here a leaf boundary
/// is seen from the stepped coordinate's low bits and costs a mask test in the
/// cached lower internal node; the voxel offset inside a leaf moves by a
/// constant stride per step; the nearest face is chosen without branches. Over
/// tiles the walk switches to 8-voxel steps whose face times come from its
/// own (next + k·delta, no division), and back, placing the voxel state from
/// the block's face times, so the state stays that of an uninterrupted walk.
/// Tested against a plane-crossing sum that uses no walk at all
/// (tests/haptic/shaft/TestShaftIntegration.cpp, ExactVoxelWalk).
///
/// The recurrences are those of openvdb::math::DDA<Ray, 0>::init/step (next =
/// t0 + (face − p)·inv, next += delta), so chords agree with it to round-off.
///
/// The damping alone (no labels, the servo's exact strategy) goes through
/// sumVoxels(), the same walk taken a major-axis cell at a time inside leaves,
/// with no dependency chain from voxel to voxel (see there).
#pragma once

#include "haptic/shaft/detail/Traversal.h"

#include <openvdb/openvdb.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

namespace voxhap::haptic::detail {

/// @brief What one grid holds where the walk is: a leaf's buffer, or the value
/// and aligned block side (8, 128, 4096) of a uniform region.
template <typename TreeT> struct WalkCursor {
    using ValueT = typename TreeT::ValueType;
    using LeafT = typename TreeT::LeafNodeType;
    /// The lower internal node: 16³ children, each a leaf or an 8³ tile.
    using NodeT = typename TreeT::RootNodeType::ChildNodeType::ChildNodeType;
    static_assert(LeafT::DIM == 8, "the walk's leaf arithmetic assumes 8³ leaves");
    static constexpr int kNodeMask = ~int(NodeT::DIM - 1);

    explicit WalkCursor(const TreeT& tree) : acc(tree), allFinite(allValuesFinite(tree)) { }
    WalkCursor(const WalkCursor& o)
        : acc(o.acc.tree()), allFinite(o.allFinite) { } // a fresh accessor per copy (one per thread)
    WalkCursor& operator=(const WalkCursor&) = delete;

    /// Move to the block of @p c. The lower internal node is kept while the walk
    /// stays in its 128³ region, so crossing into a neighbouring leaf is a mask
    /// test and a table read, not a tree query.
    [[gnu::always_inline]] void at(const openvdb::Coord& c) noexcept
    {
        const openvdb::Coord o(c.x() & kNodeMask, c.y() & kNodeMask, c.z() & kNodeMask);
        if (o != nodeOrigin) enterNode(o, c);
        if (node) {
            const openvdb::Index n = NodeT::coordToOffset(c);
            const auto& entry = node->getTable()[n];
            if (node->isChildMaskOn(n)) {
                data = entry.getChild()->buffer().data();
                dim = 0;
            } else {
                data = nullptr;
                constant = entry.getValue();
                dim = int(LeafT::DIM);
            }
            return;
        }
        // Above the lower internal level: an upper internal tile (128³), a root
        // tile or the background (aligned 4096³ blocks).
        data = nullptr;
        constant = acc.getValue(c);
        dim = acc.getValueDepth(c) == 1 ? int(NodeT::DIM) : 4096;
    }
    [[gnu::noinline]] void enterNode(const openvdb::Coord& o, const openvdb::Coord& c) noexcept
    {
        nodeOrigin = o;
        node = acc.template probeConstNode<NodeT>(c);
    }
    ValueT read(unsigned offset) const noexcept { return data ? data[offset] : constant; }

    /// Whether every value the walk can read (leaf voxels active or not, tiles,
    /// background) is finite: then sums need not test each one.
    static bool allValuesFinite(const TreeT& tree)
    {
        if constexpr (!std::is_floating_point_v<ValueT>) {
            return true;
        } else {
            if (!std::isfinite(tree.background())) return false;
            for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
                const ValueT* v = leaf->buffer().data();
                bool finite = true;
                for (openvdb::Index i = 0; i < LeafT::SIZE; ++i) finite &= std::isfinite(v[i]);
                if (!finite) return false;
            }
            auto tile = tree.cbeginValueAll(); // tiles only: the leaves' values were read above
            tile.setMaxDepth(decltype(tile)::LEAF_DEPTH - 1);
            for (; tile; ++tile) {
                if (!std::isfinite(*tile)) return false;
            }
            return true;
        }
    }

    openvdb::tree::ValueAccessor<const TreeT> acc;
    const NodeT* node = nullptr;
    openvdb::Coord nodeOrigin{std::numeric_limits<int>::max()};
    const ValueT* data = nullptr;
    ValueT constant{};
    int dim = 0; ///< 0 in a leaf
    bool allFinite;
};

/// @brief Walk the voxel cells of @p s over [t0, t1] (shifted frame: cell c is
/// [c, c+1)³). For each cell with a positive chord, voxel(ta, tb, unsigned
/// offset, cursors...) is called inside a leaf of any cursor, and run(ta, tb)
/// once per uniform block crossed when every cursor is uniform there (read
/// the cursors' constants). Cursors are refreshed before either is called.
template <typename Voxel, typename Run, typename... Cursor>
inline void walkVoxels(
    const IndexSegment& s, double t0, double t1, Voxel&& voxel, Run&& run, Cursor&... cursors) noexcept
{
    constexpr double kNever = std::numeric_limits<double>::max();
    constexpr unsigned kStride[3] = {64u, 8u, 1u}; // LeafNode::coordToOffset: x·64 + y·8 + z
    int c[3], step[3], wrap[3];
    unsigned stride[3];
    double next[3], delta[3], absD[3]; // absD = 1/delta: voxel faces per unit t
    for (int i = 0; i < 3; ++i) {
        const double p = s.a[i] + s.d[i] * t0;
        c[i] = int(std::floor(p));
        absD[i] = std::abs(s.d[i]);
        if (s.d[i] == 0.0) {
            step[i] = 0;
            next[i] = delta[i] = kNever;
            wrap[i] = -1; // never matches c & 7
            stride[i] = 0;
            continue;
        }
        const double inv = 1.0 / s.d[i];
        if (s.d[i] > 0.0) {
            step[i] = 1;
            next[i] = t0 + (double(c[i]) + 1.0 - p) * inv;
            delta[i] = inv;
            wrap[i] = 0; // stepping up into a new leaf lands on local 0
            stride[i] = kStride[i];
        } else {
            step[i] = -1;
            next[i] = t0 + (double(c[i]) - p) * inv;
            delta[i] = -inv;
            wrap[i] = 7; // stepping down into a new leaf lands on local 7
            stride[i] = 0u - kStride[i];
        }
    }
    const auto refresh = [&] {
        const openvdb::Coord cc(c[0], c[1], c[2]);
        (cursors.at(cc), ...);
    };
    const auto local = [&] { return unsigned(((c[0] & 7) << 6) | ((c[1] & 7) << 3) | (c[2] & 7)); };
    refresh();
    double t = t0;
    for (;;) {
        int uniform = 4096;
        ((uniform = cursors.dim < uniform ? cursors.dim : uniform), ...);
        if (uniform > 8) {
            // Leave the aligned block at its first face: on axis i that face is
            // k more voxel faces beyond next[i].
            // (Axes the segment does not move along have next = delta = kNever:
            // their face is never the nearest and they never advance.)
            double exit = t1;
            int exitAxis = -1, exitSteps = 0;
            for (int i = 0; i < 3; ++i) {
                const int lo = c[i] & ~(uniform - 1);
                const int k = step[i] > 0 ? lo + uniform - 1 - c[i] : c[i] - lo;
                const double face = next[i] + double(k) * delta[i];
                const bool nearer = face < exit;
                exit = nearer ? face : exit;
                exitAxis = nearer ? i : exitAxis;
                exitSteps = nearer ? k + 1 : exitSteps;
            }
            if (exit > t) run(t, exit);
            if (exitAxis < 0) return; // the segment ends inside the block
            for (int i = 0; i < 3; ++i) {
                // Faces of axis i crossed up to the exit: those at next + m·delta <= exit.
                const int crossed = std::max(0, int(std::floor((exit - next[i]) * absD[i])) + 1);
                const int n = i == exitAxis ? exitSteps : step[i] == 0 ? 0 : crossed;
                c[i] += n * step[i];
                next[i] += double(n) * delta[i];
            }
            t = exit;
            refresh();
            continue;
        }
        if (uniform == 8) {
            // A run of 8³ tiles: step block by block (openvdb's level-3 DDA, on the
            // walk's own face times: the block's far face on axis i is k voxel faces
            // beyond next[i]) until a block holds a leaf, then resume voxel steps.
            int b[3];
            double bnext[3], bdelta[3];
            for (int i = 0; i < 3; ++i) {
                b[i] = c[i] & ~7;
                const int k = step[i] > 0 ? b[i] + 7 - c[i] : c[i] - b[i];
                bnext[i] = next[i] + double(k) * delta[i];
                bdelta[i] = 8.0 * delta[i];
            }
            int axis = 0;
            for (;;) {
                const double n0 = bnext[0], n1 = bnext[1], n2 = bnext[2];
                const bool y = n1 < n0;
                const double m01 = y ? n1 : n0;
                const bool z = n2 < m01;
                axis = z ? 2 : int(y);
                const double tn = z ? n2 : m01;
                const double tb = tn < t1 ? tn : t1;
                if (tb > t) run(t, tb);
                if (!(tn < t1)) return;
                t = tn;
                bnext[axis] += bdelta[axis];
                b[axis] += 8 * step[axis];
                const openvdb::Coord bc(b[0], b[1], b[2]);
                (cursors.at(bc), ...);
                bool leaf = false;
                ((leaf = leaf || cursors.dim == 0), ...);
                if (leaf) break;
            }
            // Entered block b through its face on @c axis at time t: the voxel
            // there, and on the other axes the voxel whose far face is the first
            // of the block's voxel faces (bnext − m·delta) beyond t.
            for (int i = 0; i < 3; ++i) {
                if (step[i] == 0) continue; // c[i] never changes
                if (i == axis) {
                    c[i] = step[i] > 0 ? b[i] : b[i] + 7;
                    next[i] = t + delta[i];
                    continue;
                }
                const double faces = std::ceil((bnext[i] - t) * absD[i]); // voxel faces of the block still ahead
                const int ahead = faces < 1.0 ? 1 : faces > 8.0 ? 8 : int(faces);
                c[i] = step[i] > 0 ? b[i] + 8 - ahead : b[i] + ahead - 1;
                next[i] = bnext[i] - double(ahead - 1) * delta[i];
            }
            continue;
        }
        unsigned offset = local();
        for (;;) {
            // The nearest face, without branches (the axis order is data-dependent,
            // so a branch here mispredicts about every other voxel); ties go to the lower axis.
            const double n0 = next[0], n1 = next[1], n2 = next[2];
            const bool y = n1 < n0;
            const double m01 = y ? n1 : n0;
            const bool z = n2 < m01;
            const int axis = z ? 2 : int(y);
            const double tn = z ? n2 : m01;
            const double tb = tn < t1 ? tn : t1;
            if (tb > t) voxel(t, tb, offset, cursors...);
            if (!(tn < t1)) return;
            t = tn;
            next[axis] += delta[axis];
            c[axis] += step[axis];
            if ((c[axis] & 7) == wrap[axis]) break; // into the next leaf
            offset += stride[axis];
        }
        refresh();
    }
}

namespace walk {

/// @brief One axis of a voxel walk: the recurrences of
/// openvdb::math::DDA<Ray, 0>::init/step (next = t0 + (face − p)·inv, next += delta).
struct Axis {
    int c = 0;           ///< cell index
    int step = 0;        ///< +1, −1, or 0 where the segment does not move along the axis
    unsigned stride = 0; ///< change of the leaf offset per step (LeafNode::coordToOffset: x·64 + y·8 + z)
    double next = 0;     ///< t of the next face
    double delta = 0;    ///< t between faces
    double absD = 0;     ///< faces per unit t (1/delta; 0 if the axis never steps)

    /// Steps the axis can still take inside the current 8³ block (8: it never steps).
    int leftInLeaf() const noexcept { return step > 0 ? 7 - (c & 7) : step < 0 ? (c & 7) : 8; }
};

/// By value, unlike std::min and std::max, so that the compiler emits minsd and
/// maxsd instead of selecting an address.
inline double minOf(double a, double b) noexcept { return b < a ? b : a; }
inline double maxOf(double a, double b) noexcept { return a < b ? b : a; }

/// @brief The A and B axes of a slab side by side: one compare, one select
/// and one add serve both. ScalarPair is two plain doubles; SimdPair, where
/// SSE2 is available (every x86-64), one register. The walk takes either (the
/// tests run both).
struct ScalarPair {
    double va, vb;
    static ScalarPair of(double a, double b) noexcept { return {a, b}; }
    static ScalarPair splat(double x) noexcept { return {x, x}; }
    double a() const noexcept { return va; }
    double b() const noexcept { return vb; }
};
inline ScalarPair minOf(ScalarPair x, ScalarPair y) noexcept { return {minOf(x.va, y.va), minOf(x.vb, y.vb)}; }
inline ScalarPair maxOf(ScalarPair x, ScalarPair y) noexcept { return {maxOf(x.va, y.va), maxOf(x.vb, y.vb)}; }
/// Lanes of x below y, as bits (1: A, 2: B) and as a mask for addWhere().
inline int below(ScalarPair x, ScalarPair y, ScalarPair& mask) noexcept
{
    mask = {x.va < y.va ? 1.0 : 0.0, x.vb < y.vb ? 1.0 : 0.0};
    return int(x.va < y.va) | int(x.vb < y.vb) << 1;
}
/// x + d in the lanes of @p mask, x elsewhere.
inline ScalarPair addWhere(ScalarPair x, ScalarPair d, ScalarPair mask) noexcept
{
    return {mask.va != 0.0 ? x.va + d.va : x.va, mask.vb != 0.0 ? x.vb + d.vb : x.vb};
}
/// The lanes in order: @return 1 if a <= b.
inline int order(ScalarPair x, double& lo, double& hi) noexcept
{
    lo = minOf(x.va, x.vb);
    hi = maxOf(x.va, x.vb);
    return int(x.va <= x.vb);
}

#if defined(__SSE2__)
struct SimdPair {
    __m128d v;
    static SimdPair of(double a, double b) noexcept { return {_mm_set_pd(b, a)}; }
    static SimdPair splat(double x) noexcept { return {_mm_set1_pd(x)}; }
    double a() const noexcept { return _mm_cvtsd_f64(v); }
    double b() const noexcept { return _mm_cvtsd_f64(_mm_unpackhi_pd(v, v)); }
};
// _mm_min_pd(y, x) is (y < x ? y : x) per lane, minOf(double) exactly, NaN included.
inline SimdPair minOf(SimdPair x, SimdPair y) noexcept { return {_mm_min_pd(y.v, x.v)}; }
inline SimdPair maxOf(SimdPair x, SimdPair y) noexcept { return {_mm_max_pd(y.v, x.v)}; }
inline int below(SimdPair x, SimdPair y, SimdPair& mask) noexcept
{
    mask.v = _mm_cmplt_pd(x.v, y.v);
    return _mm_movemask_pd(mask.v);
}
/// Without a branch: GCC does not if-convert a floating-point add (it may
/// trap), and as a branch this data-dependent condition mispredicts often.
inline SimdPair addWhere(SimdPair x, SimdPair d, SimdPair mask) noexcept
{
    return {_mm_add_pd(x.v, _mm_and_pd(mask.v, d.v))};
}
/// Without a branch as well: which of A and B comes first is data-dependent.
inline int order(SimdPair x, double& lo, double& hi) noexcept
{
    const __m128d swapped = _mm_shuffle_pd(x.v, x.v, 1);
    lo = _mm_cvtsd_f64(_mm_min_pd(swapped, x.v));
    hi = _mm_cvtsd_f64(_mm_max_pd(swapped, x.v));
    return _mm_movemask_pd(_mm_cmple_pd(x.v, swapped)) & 1;
}
using Pair = SimdPair;
#else
using Pair = ScalarPair;
#endif

/// A voxel value as the sum counts it: non-finite values count nothing (a
/// grid known to hold none skips the test: Finite).
template <bool Finite> inline double counted(float v) noexcept
{
    if constexpr (Finite) {
        return double(v);
    } else {
        return std::isfinite(v) ? double(v) : 0.0;
    }
}

/// sumVoxels() with its major axis M fixed at compile time, so that the walk's
/// state lives in registers (no axis-indexed arrays).
template <int M, bool Finite, typename PairT, typename Cursor>
double sumAlong(Axis x, Axis y, Axis z, double t, double t1, Cursor& cursor) noexcept
{
    const auto counted = [](float v) { return walk::counted<Finite>(v); };
    constexpr int A = M == 0 ? 1 : 0, B = M == 2 ? 1 : 2;
    Axis& m = M == 0 ? x : M == 1 ? y : z;
    Axis& a = A == 0 ? x : y;
    Axis& b = B == 1 ? y : z;
    const auto each = [&](auto&& f) {
        f(x, 0);
        f(y, 1);
        f(z, 2);
    };
    double sum = 0.0;
    cursor.at(openvdb::Coord(x.c, y.c, z.c));
    for (;;) {
        const int uniform = cursor.dim;
        if (uniform > 8) {
            // As walkVoxels(): leave the aligned block at its first face.
            double exit = t1;
            int exitAxis = -1, exitSteps = 0;
            each([&](const Axis& w, int i) {
                const int lo = w.c & ~(uniform - 1);
                const int k = w.step > 0 ? lo + uniform - 1 - w.c : w.c - lo;
                const double face = w.next + double(k) * w.delta;
                if (face < exit) exit = face, exitAxis = i, exitSteps = k + 1;
            });
            if (exit > t) sum += counted(cursor.constant) * (exit - t);
            if (exitAxis < 0) return sum;
            each([&](Axis& w, int i) {
                const int crossed = std::max(0, int(std::floor((exit - w.next) * w.absD)) + 1);
                const int n = i == exitAxis ? exitSteps : w.step == 0 ? 0 : crossed;
                w.c += n * w.step;
                w.next += double(n) * w.delta;
            });
            t = exit;
            cursor.at(openvdb::Coord(x.c, y.c, z.c));
            continue;
        }
        if (uniform == 8) {
            // As walkVoxels(): a run of 8³ tiles block by block, until a block holds a leaf.
            struct Block {
                int b;
                double next, delta;
            };
            const auto block = [](const Axis& w) {
                const int lo = w.c & ~7;
                const int k = w.step > 0 ? lo + 7 - w.c : w.c - lo;
                return Block{lo, w.next + double(k) * w.delta, 8.0 * w.delta};
            };
            Block bx = block(x), by = block(y), bz = block(z);
            // Inside the cursor's node a block step is a step of its table index, as in
            // the leaf loop below; out of it, the cursor finds what is there.
            const typename Cursor::NodeT* const node = cursor.node;
            constexpr unsigned kTs[3] = {256u, 16u, 1u};
            const auto leavesLeft = [](const Axis& w) {
                const int l = (w.c >> 3) & 15;
                return w.step > 0 ? 15 - l : w.step < 0 ? l : 16;
            };
            int nodeLeft[3] = {leavesLeft(x), leavesLeft(y), leavesLeft(z)};
            const unsigned ts[3] = {x.step < 0 ? 0u - kTs[0] : kTs[0], y.step < 0 ? 0u - kTs[1] : kTs[1],
                z.step < 0 ? 0u - kTs[2] : kTs[2]};
            unsigned n = unsigned((((x.c >> 3) & 15) << 8) | (((y.c >> 3) & 15) << 4) | ((z.c >> 3) & 15));
            double value = counted(cursor.constant);
            int axis = 0;
            for (;;) {
                const bool ya = by.next < bx.next;
                const double m01 = ya ? by.next : bx.next;
                const bool za = bz.next < m01;
                axis = za ? 2 : int(ya);
                const double tn = za ? bz.next : m01;
                const double tb = minOf(tn, t1);
                if (tb > t) sum += value * (tb - t);
                if (!(tn < t1)) return sum;
                t = tn;
                Block& bb = axis == 0 ? bx : axis == 1 ? by : bz;
                bb.next += bb.delta;
                bb.b += 8 * (axis == 0 ? x.step : axis == 1 ? y.step : z.step);
                if (nodeLeft[axis] == 0) {
                    cursor.at(openvdb::Coord(bx.b, by.b, bz.b));
                    break;
                }
                --nodeLeft[axis];
                n += ts[axis];
                if (node->isChildMaskOn(n)) { // a leaf, left as cursor.at() leaves it
                    cursor.data = node->getTable()[n].getChild()->buffer().data();
                    cursor.dim = 0;
                    break;
                }
                value = counted(node->getTable()[n].getValue());
            }
            // Entered block b through its face on `axis` at time t: the voxel there,
            // and on the other axes the voxel whose far face is the first of the
            // block's voxel faces (bnext − m·delta) beyond t.
            each([&](Axis& w, int i) {
                const Block& bb = i == 0 ? bx : i == 1 ? by : bz;
                if (w.step == 0) return; // c never changes
                if (i == axis) {
                    w.c = w.step > 0 ? bb.b : bb.b + 7;
                    w.next = t + w.delta;
                    return;
                }
                const double faces = std::ceil((bb.next - t) * w.absD); // voxel faces of the block still ahead
                const int ahead = faces < 1.0 ? 1 : faces > 8.0 ? 8 : int(faces);
                w.c = w.step > 0 ? bb.b + 8 - ahead : bb.b + ahead - 1;
                w.next = bb.next - double(ahead - 1) * w.delta;
            });
            continue;
        }
        // In a leaf, slab by slab along M. left* counts the steps an axis can still
        // take inside the leaf, nodeLeft* the leaves it can still enter inside the
        // cursor's lower internal node (128³, a 16³ table of leaves and tiles).
        // Into a neighbouring leaf of that node is a step of the table index and
        // a child-mask test; into a tile or out of the node, the cell is written
        // back and cursor.at() takes over.
        using NodeT = typename Cursor::NodeT;
        const NodeT* const node = cursor.node;
        const auto* data = cursor.data;
        int leftM = m.leftInLeaf(), leftA = a.leftInLeaf(), leftB = b.leftInLeaf();
        const auto leavesLeft = [](const Axis& w) {
            const int l = (w.c >> 3) & 15;
            return w.step > 0 ? 15 - l : w.step < 0 ? l : 16;
        };
        int nodeLeftM = leavesLeft(m), nodeLeftA = leavesLeft(a), nodeLeftB = leavesLeft(b);
        constexpr unsigned kTableStride[3] = {256u, 16u, 1u}; // InternalNode<Leaf, 4>::coordToOffset
        const unsigned tsM = m.step < 0 ? 0u - kTableStride[M] : kTableStride[M];
        const unsigned tsA = a.step < 0 ? 0u - kTableStride[A] : kTableStride[A];
        const unsigned tsB = b.step < 0 ? 0u - kTableStride[B] : kTableStride[B];
        unsigned n = unsigned((((x.c >> 3) & 15) << 8) | (((y.c >> 3) & 15) << 4) | ((z.c >> 3) & 15));
        double nM = m.next;
        PairT nAB = PairT::of(a.next, b.next);
        const double dM = m.delta;
        const PairT dAB = PairT::of(a.delta, b.delta);
        const unsigned strM = m.stride, strA = a.stride, strB = b.stride;
        unsigned off = unsigned(((x.c & 7) << 6) | ((y.c & 7) << 3) | (z.c & 7));
        int outOfNode = -1; // the axis whose step leaves the node (not yet taken in n and off)
        // One step into the next leaf along an axis (whose left is 0): false if that
        // block is not a leaf of this node.
        const auto crossLeaf = [&](int& left, int& nodeLeft, unsigned ts, unsigned str, int axis) {
            if (nodeLeft == 0) {
                outOfNode = axis;
                return false;
            }
            --nodeLeft;
            n += ts;
            off -= 7u * str; // the local coordinate wraps from 7 to 0, or from 0 to 7
            left = 7;
            if (!node->isChildMaskOn(n)) return false;
            data = node->getTable()[n].getChild()->buffer().data();
            return true;
        };
        for (;;) {
            const double te = minOf(nM, t1);
            const PairT teAB = PairT::splat(te);
            PairT crossing;
            const int bits = below(nAB, teAB, crossing); // faces of A and B inside the slab
            const int xa = bits & 1, xb = bits >> 1;
            const int nextLeftA = leftA - xa, nextLeftB = leftB - xb;
            if ((nextLeftA | nextLeftB) < 0) [[unlikely]] {
                // A face of A or B in this slab is the leaf's: one step to the nearer of them.
                double nA = nAB.a(), nB = nAB.b();
                const bool stepA = xa && (!xb || nA <= nB);
                const double tx = maxOf(stepA ? nA : nB, t);
                sum += counted(data[off]) * (tx - t);
                t = tx;
                bool inLeaf = true;
                if (stepA) {
                    nA += a.delta;
                    if (leftA == 0) {
                        inLeaf = crossLeaf(leftA, nodeLeftA, tsA, strA, A);
                    } else {
                        --leftA;
                        off += strA;
                    }
                } else {
                    nB += b.delta;
                    if (leftB == 0) {
                        inLeaf = crossLeaf(leftB, nodeLeftB, tsB, strB, B);
                    } else {
                        --leftB;
                        off += strB;
                    }
                }
                nAB = PairT::of(nA, nB);
                if (!inLeaf) break;
                continue;
            }
            // Up to three voxels: v0 until the first face of A or B, v1 until the
            // second, v2 to the end of the slab (absent faces are at te).
            double tf, tl;
            const int aFirst = order(minOf(maxOf(nAB, PairT::splat(t)), teAB), tf, tl);
            const unsigned oA = strA & (0u - unsigned(xa)), oB = strB & (0u - unsigned(xb));
            const unsigned o1 = off + oB + ((oA - oB) & (0u - unsigned(aFirst))), o2 = off + oA + oB;
            sum += (counted(data[off]) * (tf - t) + counted(data[o1]) * (tl - tf)) + counted(data[o2]) * (te - tl);
            nAB = addWhere(nAB, dAB, crossing);
            leftA = nextLeftA;
            leftB = nextLeftB;
            off = o2;
            if (!(nM < t1)) return sum;
            t = nM;
            nM += dM;
            if (leftM == 0) {
                if (!crossLeaf(leftM, nodeLeftM, tsM, strM, M)) break;
            } else {
                --leftM;
                off += strM;
            }
        }
        // The cell from the table index and the leaf offset, plus the step out of the node if any.
        const openvdb::Coord& o = cursor.nodeOrigin;
        x.c = o.x() + int(((n >> 8) & 15) << 3) + int((off >> 6) & 7) + (outOfNode == 0 ? x.step : 0);
        y.c = o.y() + int(((n >> 4) & 15) << 3) + int((off >> 3) & 7) + (outOfNode == 1 ? y.step : 0);
        z.c = o.z() + int((n & 15) << 3) + int(off & 7) + (outOfNode == 2 ? z.step : 0);
        m.next = nM, a.next = nAB.a(), b.next = nAB.b();
        cursor.at(openvdb::Coord(x.c, y.c, z.c));
    }
}

} // namespace walk

/// @brief Σ value × chord (in t units) over the voxel cells of @p s (shifted
/// frame) inside the box [lo, hi], non-finite values counting nothing:
/// walkVoxels() for one grid and no labels, with the voxel steps inside a
/// leaf taken a major-axis cell at a time.
///
/// Why: walkVoxels() picks the nearest of three faces per voxel, and the next
/// pick waits for the last one (compare, select, load and add through the
/// axis-indexed state: a dependency chain of some 25 cycles per voxel, which is
/// what the walk cost on real data, where nearly every voxel is in a leaf).
/// Along the axis M where the segment moves fastest in index units, each cell
/// of M (a "slab") holds at most one face of each other axis, since their faces
/// are at least as far apart in t. So a slab is up to three voxels whose order
/// comes from one comparison, every choice is a select, and the chain from one
/// slab to the next is one add per axis: successive slabs overlap in the
/// processor. A slab whose other-axis face is also the leaf's takes plain
/// single steps; a step into a neighbouring leaf of the same 128³ node is a
/// step of the node's table index. Face times follow the recurrences of
/// walkVoxels(), so the sums differ from it by round-off only (and from the
/// exact chord sum by a few ulps of the crossing times: tested against a sum
/// over sorted plane crossings, both lane types, with and without NaN).
template <typename Cursor, typename PairT = walk::Pair>
inline double sumVoxels(
    const IndexSegment& s, const openvdb::Vec3d& lo, const openvdb::Vec3d& hi, Cursor& cursor) noexcept
{
    // Clip [0, 1] to the box (slab method, as clip()) with the reciprocals the walk uses too.
    double inv[3], t0 = 0.0, t1 = 1.0;
    for (int i = 0; i < 3; ++i) {
        inv[i] = 0.0;
        if (s.d[i] == 0.0) {
            if (s.a[i] < lo[i] || s.a[i] > hi[i]) return 0.0;
            continue;
        }
        inv[i] = 1.0 / s.d[i];
        const double ta = (lo[i] - s.a[i]) * inv[i], tb = (hi[i] - s.a[i]) * inv[i];
        t0 = walk::maxOf(t0, walk::minOf(ta, tb));
        t1 = walk::minOf(t1, walk::maxOf(ta, tb));
    }
    if (!(t0 < t1)) return 0.0;
    constexpr double kNever = std::numeric_limits<double>::max();
    constexpr unsigned kStride[3] = {64u, 8u, 1u};
    walk::Axis ax[3];
    // Most shafts start inside the box (t0 = 0, p = a): a predicted branch lets the
    // walk's set-up start before the clip's divisions are done.
    const bool fromEntry = t0 == 0.0;
    for (int i = 0; i < 3; ++i) {
        walk::Axis& w = ax[i];
        const double p = fromEntry ? s.a[i] : s.a[i] + s.d[i] * t0;
        w.c = int(std::floor(p));
        w.absD = std::abs(s.d[i]);
        if (s.d[i] == 0.0) {
            w.next = w.delta = kNever;
            continue;
        }
        w.step = s.d[i] > 0.0 ? 1 : -1;
        w.next = t0 + (double(w.c) + (s.d[i] > 0.0 ? 1.0 : 0.0) - p) * inv[i];
        w.delta = std::abs(inv[i]);
        w.stride = s.d[i] > 0.0 ? kStride[i] : 0u - kStride[i];
    }
    // The major axis: the largest |d| (smallest delta).
    const double d0 = ax[0].absD, d1 = ax[1].absD, d2 = ax[2].absD;
    const int major = d0 >= d1 && d0 >= d2 ? 0 : d1 >= d2 ? 1 : 2;
    const auto along = [&]<bool Finite>() {
        if (major == 0) return walk::sumAlong<0, Finite, PairT>(ax[0], ax[1], ax[2], t0, t1, cursor);
        if (major == 1) return walk::sumAlong<1, Finite, PairT>(ax[0], ax[1], ax[2], t0, t1, cursor);
        return walk::sumAlong<2, Finite, PairT>(ax[0], ax[1], ax[2], t0, t1, cursor);
    };
    return cursor.allFinite ? along.template operator()<true>() : along.template operator()<false>();
}

/// @brief The exact piecewise-constant pass over voxel cells (s in the shifted
/// frame, box [lo, hi] of voxel cells): chord-weighted β into out.dampingIntegral
/// when @p beta is given, label lengths and first hits when @p labels is given.
/// A non-finite voxel contributes nothing. The walk is voxelWalk (VoxelWalk.h).
/// @p offsetMm: where s starts along a polyline (first hits are measured from its start).
template <typename BetaCursor, typename LabelCursor>
inline void chordPass(const IndexSegment& s, const openvdb::Vec3d& lo, const openvdb::Vec3d& hi, BetaCursor* beta,
    LabelCursor* labels, ShaftIntegral& out, double offsetMm = 0.0) noexcept
{
    if (beta && !labels) { // the damping alone: sumVoxels() clips and walks
        out.dampingIntegral = sumVoxels(s, lo, hi, *beta) * s.lengthMm;
        return;
    }
    double t0 = 0.0, t1 = 0.0;
    const bool inside = clip(s, lo, hi, t0, t1);
    LabelTally tally(out, s.lengthMm, offsetMm);
    if (!inside) {
        if (labels) tally.add(0, 0.0, 1.0); // all air
        return;
    }
    if (labels && t0 > 0.0) tally.add(0, 0.0, t0);
    double sum = 0.0;
    const auto addBeta = [&sum](float b, double ta, double tb) {
        if (std::isfinite(b)) sum += double(b) * (tb - ta);
    };
    if (beta && labels) {
        walkVoxels(
            s, t0, t1,
            [&](double ta, double tb, unsigned o, const BetaCursor& bc, const LabelCursor& lc) {
                addBeta(bc.read(o), ta, tb);
                tally.add(lc.read(o), ta, tb);
            },
            [&](double ta, double tb) {
                addBeta(beta->constant, ta, tb);
                tally.add(labels->constant, ta, tb);
            },
            *beta, *labels);
    } else if (labels) {
        walkVoxels(
            s, t0, t1, [&](double ta, double tb, unsigned o, const LabelCursor& lc) { tally.add(lc.read(o), ta, tb); },
            [&](double ta, double tb) { tally.add(labels->constant, ta, tb); }, *labels);
    }
    if (labels && t1 < 1.0) tally.add(0, t1, 1.0);
    if (beta) out.dampingIntegral = sum * s.lengthMm;
}

/// @brief chordPass along a polyline (architecture.md "Shaft integration"): the
/// segments' integrals summed, first hits measured from its first point; zero
/// integrals for a non-finite point or fewer than two points.
template <typename IndexMap, typename BetaCursor, typename LabelCursor>
inline void polylineChordPass(const IndexMap& xf, std::span<const Vec3d> points, const openvdb::Vec3d& lo,
    const openvdb::Vec3d& hi, BetaCursor* beta, LabelCursor* labels, ShaftIntegral& out) noexcept
{
    if (!polylineValid(points)) return;
    eachSegment(xf, points, 0.5, out,
        [&](const IndexSegment& s, double offset) { chordPass(s, lo, hi, beta, labels, out, offset); });
}

} // namespace voxhap::haptic::detail
