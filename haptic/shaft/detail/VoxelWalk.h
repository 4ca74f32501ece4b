// SPDX-License-Identifier: Apache-2.0
/// @file VoxelWalk.h
/// @brief The exact chord pass and its walk: one Amanatides–Woo voxel walk that never
/// restarts, reading each 8³ leaf's buffer directly and jumping across uniform
/// blocks (tiles, background) in one step.
///
/// Why not openvdb::math::DDA with a leaf reader (walkCellsSkipping): on a real
/// CT nearly every block crossed is a leaf, and that walk paid at every block
/// boundary for an exit computed with three divisions, a DDA restarted from
/// scratch and three tree queries. Here a leaf boundary is seen from the
/// stepped coordinate's low bits, costs one cached-accessor probe, and the
/// voxel offset inside a leaf moves by a constant stride per step. A uniform
/// block is left at the earliest of its faces, found from the walk's own face
/// times (next + k·delta, no division); the walk then moves every axis to that
/// time, so the state stays that of an uninterrupted walk.
///
/// The recurrences are those of openvdb::math::DDA<Ray, 0>::init/step (next =
/// t0 + (face − p)·inv, next += delta), so chords agree with it to round-off.
#pragma once

#include "haptic/shaft/detail/Traversal.h"

#include <openvdb/openvdb.h>

#include <cmath>
#include <limits>

namespace voxhap::haptic::detail {

/// @brief What one grid holds where the walk is: a leaf's buffer, or the value
/// and aligned block side (8, 128, 4096) of a uniform region.
template <typename TreeT> struct WalkCursor {
    using ValueT = typename TreeT::ValueType;
    using LeafT = typename TreeT::LeafNodeType;
    static_assert(LeafT::DIM == 8, "the walk's leaf arithmetic assumes 8³ leaves");

    explicit WalkCursor(const TreeT& tree) : acc(tree) { }
    WalkCursor(const WalkCursor& o) : acc(o.acc.tree()) { } // a fresh accessor per copy (one per thread)
    WalkCursor& operator=(const WalkCursor&) = delete;

    void at(const openvdb::Coord& c) noexcept
    {
        if (const LeafT* leaf = acc.probeConstLeaf(c)) {
            data = leaf->buffer().data();
            dim = 0;
            return;
        }
        data = nullptr;
        constant = acc.getValue(c);
        // Depth at which the value lives: 1 upper internal tile (128³), 2 lower
        // internal tile (8³); 0 root tile or -1 background (4096³ aligned blocks).
        const int depth = acc.getValueDepth(c);
        dim = depth == 1 ? 128 : depth == 2 ? 8 : 4096;
    }
    ValueT read(unsigned offset) const noexcept { return data ? data[offset] : constant; }

    openvdb::tree::ValueAccessor<const TreeT> acc;
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
    double next[3], delta[3];
    for (int i = 0; i < 3; ++i) {
        const double p = s.a[i] + s.d[i] * t0;
        c[i] = int(std::floor(p));
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
        if (uniform > 1) {
            // Leave the aligned block at its first face: on axis i that face is
            // k more voxel faces beyond next[i].
            double exit = t1;
            int exitAxis = -1, exitSteps = 0;
            for (int i = 0; i < 3; ++i) {
                if (step[i] == 0) continue;
                const int lo = c[i] & ~(uniform - 1);
                const int k = step[i] > 0 ? lo + uniform - 1 - c[i] : c[i] - lo;
                const double face = next[i] + double(k) * delta[i];
                if (face < exit) {
                    exit = face;
                    exitAxis = i;
                    exitSteps = k + 1;
                }
            }
            if (exit > t) run(t, exit);
            if (exitAxis < 0) return; // the segment ends inside the block
            for (int i = 0; i < 3; ++i) {
                if (step[i] == 0) continue;
                int n = 0;
                if (i == exitAxis) {
                    n = exitSteps;
                } else if (next[i] <= exit) {
                    n = int(std::floor((exit - next[i]) / delta[i])) + 1;
                }
                c[i] += n * step[i];
                next[i] += double(n) * delta[i];
            }
            t = exit;
            refresh();
            continue;
        }
        unsigned offset = local();
        for (;;) {
            const int axis = next[0] <= next[1] ? (next[0] <= next[2] ? 0 : 2) : (next[1] <= next[2] ? 1 : 2);
            const double tn = next[axis];
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
