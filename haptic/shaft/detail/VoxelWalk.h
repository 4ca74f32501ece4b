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
#pragma once

#include "haptic/shaft/detail/Traversal.h"

#include <openvdb/openvdb.h>

#include <algorithm>
#include <cmath>
#include <limits>

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

    explicit WalkCursor(const TreeT& tree) : acc(tree) { }
    WalkCursor(const WalkCursor& o) : acc(o.acc.tree()) { } // a fresh accessor per copy (one per thread)
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

    openvdb::tree::ValueAccessor<const TreeT> acc;
    const NodeT* node = nullptr;
    openvdb::Coord nodeOrigin{std::numeric_limits<int>::max()};
    const ValueT* data = nullptr;
    ValueT constant{};
    int dim = 0; ///< 0 in a leaf
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

/// @brief The exact piecewise-constant pass over voxel cells (s in the shifted
/// frame, box [lo, hi] of voxel cells): chord-weighted β into out.dampingIntegral
/// when @p beta is given, label lengths and first hits when @p labels is given.
/// A non-finite voxel contributes nothing. The walk is voxelWalk (VoxelWalk.h).
template <typename BetaCursor, typename LabelCursor>
inline void chordPass(const IndexSegment& s, const openvdb::Vec3d& lo, const openvdb::Vec3d& hi, BetaCursor* beta,
    LabelCursor* labels, ShaftIntegral& out) noexcept
{
    double t0 = 0.0, t1 = 0.0;
    const bool inside = clip(s, lo, hi, t0, t1);
    LabelTally tally(out, s.lengthMm);
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
    } else if (beta) {
        walkVoxels(
            s, t0, t1, [&](double ta, double tb, unsigned o, const BetaCursor& bc) { addBeta(bc.read(o), ta, tb); },
            [&](double ta, double tb) { addBeta(beta->constant, ta, tb); }, *beta);
    } else if (labels) {
        walkVoxels(
            s, t0, t1, [&](double ta, double tb, unsigned o, const LabelCursor& lc) { tally.add(lc.read(o), ta, tb); },
            [&](double ta, double tb) { tally.add(labels->constant, ta, tb); }, *labels);
    }
    if (labels && t1 < 1.0) tally.add(0, t1, 1.0);
    if (beta) out.dampingIntegral = sum * s.lengthMm;
}

} // namespace voxhap::haptic::detail
