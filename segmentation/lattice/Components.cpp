// SPDX-License-Identifier: Apache-2.0
/// @file Components.cpp
/// @brief Run-based union-find labelling in parallel slabs, and breadth-first
/// region growing with parallel steps.

#include "segmentation/lattice/Components.h"

#include "segmentation/detail/VoxelLoops.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <climits>
#include <stdexcept>

namespace voxhap::segmentation {

namespace {

/// Union-find over run indices whose root is always the smallest index of its
/// set: the root is then the component's first run in memory order.
struct MinRootSets {
    std::vector<std::uint32_t> parent;
    explicit MinRootSets(std::size_t n) : parent(n)
    {
        tbb::parallel_for(
            tbb::blocked_range<std::size_t>(0, n, 1 << 16), [&](const tbb::blocked_range<std::size_t>& r) {
                for (std::size_t i = r.begin(); i != r.end(); ++i) parent[i] = std::uint32_t(i);
            });
    }
    std::uint32_t find(std::uint32_t x)
    {
        while (parent[x] != x) {
            parent[x] = parent[parent[x]]; // path halving
            x = parent[x];
        }
        return x;
    }
    void unite(std::uint32_t a, std::uint32_t b)
    {
        a = find(a);
        b = find(b);
        if (a == b) return;
        if (a < b)
            parent[b] = a;
        else
            parent[a] = b;
    }
};

/// Unite the runs of two rows that overlap along axis 0 (face neighbours).
void joinRows(const ComponentRuns& c, MinRootSets& sets, std::size_t rowA, std::size_t rowB)
{
    std::size_t a = c.rowStart[rowA], b = c.rowStart[rowB];
    const std::size_t aEnd = c.rowStart[rowA + 1], bEnd = c.rowStart[rowB + 1];
    while (a < aEnd && b < bEnd) {
        const Run& ra = c.runs[a];
        const Run& rb = c.runs[b];
        if (ra.begin < rb.end && rb.begin < ra.end) sets.unite(std::uint32_t(a), std::uint32_t(b));
        // Advance the run that ends first: it can overlap nothing further on.
        if (ra.end < rb.end)
            ++a;
        else
            ++b;
    }
}

} // namespace

ComponentRuns componentRuns(const Lattice& lat, const Mask& m, Span span)
{
    ComponentRuns c;
    const int nx = lat.dims.x(), ny = lat.dims.y(), nz = lat.dims.z();
    const std::size_t rows = std::size_t(ny) * std::size_t(nz);
    // Span::Slice excludes one axis: along x, runs are single voxels; along y or z,
    // rows are not joined across it.
    const bool splitX = span == Span::Slice && lat.sliceAxis == 0;
    const bool joinY = !(span == Span::Slice && lat.sliceAxis == 1);
    const bool joinZ = !(span == Span::Slice && lat.sliceAxis == 2);
    c.rowStart.assign(rows + 1, 0);
    if (m.empty()) return c;

    const auto scanRow = [&](std::size_t row, auto&& emit) {
        const std::uint8_t* p = m.data() + row * std::size_t(nx);
        int i = 0;
        while (i < nx) {
            while (i < nx && !p[i]) ++i;
            if (i == nx) break;
            const int b = i;
            if (splitX)
                ++i;
            else
                while (i < nx && p[i]) ++i;
            emit(b, i);
        }
    };
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows, 256), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t row = r.begin(); row != r.end(); ++row) {
            std::size_t count = 0;
            scanRow(row, [&](int, int) { ++count; });
            c.rowStart[row + 1] = count;
        }
    });
    for (std::size_t row = 0; row < rows; ++row) c.rowStart[row + 1] += c.rowStart[row];
    const std::size_t total = c.rowStart[rows];
    if (total >= std::size_t(UINT32_MAX)) throw std::length_error("connected components: too many runs");
    c.runs.resize(total);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows, 256), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t row = r.begin(); row != r.end(); ++row) {
            std::size_t n = c.rowStart[row];
            scanRow(row, [&](int b, int e) { c.runs[n++] = {std::int32_t(row), b, e}; });
        }
    });

    // Slabs of whole k planes are joined in parallel (each touches only its own
    // runs), then their borders one after another.
    MinRootSets sets(total);
    const int slab = std::max(1, nz / 16);
    const int slabs = (nz + slab - 1) / slab;
    tbb::parallel_for(0, slabs, [&](int s) {
        const int k0 = s * slab, k1 = std::min(nz, k0 + slab);
        for (int k = k0; k < k1; ++k) {
            for (int j = 0; j < ny; ++j) {
                const std::size_t row = std::size_t(j) + std::size_t(ny) * std::size_t(k);
                if (joinY && j > 0) joinRows(c, sets, row - 1, row);
                if (joinZ && k > k0) joinRows(c, sets, row - std::size_t(ny), row);
            }
        }
    });
    if (joinZ) {
        for (int s = 1; s < slabs; ++s) {
            const int k = s * slab;
            for (int j = 0; j < ny; ++j) {
                const std::size_t row = std::size_t(j) + std::size_t(ny) * std::size_t(k);
                joinRows(c, sets, row - std::size_t(ny), row);
            }
        }
    }

    // Number the components by their first run; a non-root's parent precedes it.
    c.of.resize(total);
    for (std::size_t n = 0; n < total; ++n) {
        const std::uint32_t p = sets.find(std::uint32_t(n));
        if (p == n) {
            c.list.emplace_back();
            c.of[n] = std::int32_t(c.list.size());
            Component& k = c.list.back();
            k.min = Vec3i(c.runs[n].begin, c.runs[n].row % ny, c.runs[n].row / ny);
            k.max = k.min;
        } else {
            c.of[n] = c.of[p];
        }
        Component& k = c.list[std::size_t(c.of[n]) - 1];
        const Run& r = c.runs[n];
        const Vec3i lo(r.begin, r.row % ny, r.row / ny), hi(r.end - 1, r.row % ny, r.row / ny);
        k.voxels += r.end - r.begin;
        k.min = k.min.cwiseMin(lo);
        k.max = k.max.cwiseMax(hi);
    }
    return c;
}

Mask ComponentRuns::mask(const Lattice& lat, const std::vector<std::uint8_t>& keep) const
{
    Mask out(lat.size(), 0);
    forEachRun(lat, [&](std::int32_t comp, std::size_t b, std::size_t e) {
        if (keep[std::size_t(comp)]) std::fill(out.begin() + std::ptrdiff_t(b), out.begin() + std::ptrdiff_t(e), 1);
    });
    return out;
}

Components connectedComponents(const Lattice& lat, const Mask& m, Span span)
{
    ComponentRuns runs = componentRuns(lat, m, span);
    Components out;
    out.id.assign(lat.size(), 0);
    runs.forEachRun(lat, [&](std::int32_t comp, std::size_t b, std::size_t e) {
        std::fill(out.id.begin() + std::ptrdiff_t(b), out.id.begin() + std::ptrdiff_t(e), comp);
    });
    out.list = std::move(runs.list);
    return out;
}

Mask largestComponent(const Lattice& lat, const Mask& m)
{
    const ComponentRuns cc = componentRuns(lat, m, Span::Volume);
    if (cc.list.empty()) return Mask(m.size(), 0);
    const auto best = std::max_element(
        cc.list.begin(), cc.list.end(), [](const Component& a, const Component& b) { return a.voxels < b.voxels; });
    std::vector<std::uint8_t> keep(cc.list.size() + 1, 0);
    keep[std::size_t(best - cc.list.begin()) + 1] = 1;
    return cc.mask(lat, keep);
}

namespace {

/// Calls f(neighbour) for the six face neighbours of element @p n that lie in
/// the lattice, in the order −x, +x, −y, +y, −z, +z.
template <class F> void forFaceNeighbours(const Lattice& lat, std::size_t n, F&& f)
{
    const auto strides = lat.strides();
    const Vec3i p = lat.position(n);
    for (int a = 0; a < 3; ++a) {
        if (p[a] > 0) f(n - strides[std::size_t(a)]);
        if (p[a] + 1 < lat.dims[a]) f(n + strides[std::size_t(a)]);
    }
}

std::int32_t loadRelaxed(const std::int32_t* p) { return __atomic_load_n(p, __ATOMIC_RELAXED); }

} // namespace

void growRegions(const Lattice& lat, std::vector<std::int32_t>& ids, const Mask& within)
{
    // The first front: every labelled voxel, in memory order.
    std::vector<std::size_t> front;
    {
        constexpr std::size_t kBlock = 1 << 16;
        const std::size_t blocks = (ids.size() + kBlock - 1) / kBlock;
        std::vector<std::vector<std::size_t>> parts(blocks);
        tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
            for (std::size_t n = b * kBlock, e = std::min(ids.size(), n + kBlock); n < e; ++n) {
                if (ids[n]) parts[b].push_back(n);
            }
        });
        for (auto& p : parts) front.insert(front.end(), p.begin(), p.end());
    }
    // Each step reproduces the serial pass: front voxels in order, neighbours in
    // order, the first to reach a voxel labels it. The front is cut into chunks in
    // order; a chunk claims a voxel by an atomic minimum of INT32_MIN + chunk in
    // the voxel's id (unlabelled voxels hold 0, claimed ones a negative marker),
    // so the earliest chunk wins whatever the threads' timing, and within a
    // chunk its first claim. The next front is the winners in the chunks' order.
    constexpr std::size_t kChunk = 2048;
    std::int32_t* id = ids.data();
    while (!front.empty()) {
        const std::size_t chunks = (front.size() + kChunk - 1) / kChunk;
        std::vector<std::vector<std::pair<std::size_t, std::int32_t>>> claims(chunks);
        tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
            const auto marker = std::int32_t(std::int64_t(INT32_MIN) + std::int64_t(c));
            auto& mine = claims[c];
            for (std::size_t f = c * kChunk, e = std::min(front.size(), f + kChunk); f < e; ++f) {
                const std::size_t n = front[f];
                const std::int32_t label = loadRelaxed(id + n);
                forFaceNeighbours(lat, n, [&](std::size_t q) {
                    if (!within[q]) return;
                    std::int32_t cur = loadRelaxed(id + q);
                    if (cur > 0) return; // labelled in an earlier step
                    while (marker < cur &&
                        !__atomic_compare_exchange_n(id + q, &cur, marker, true, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
                    }
                    mine.emplace_back(q, label);
                });
            }
        });
        std::vector<std::vector<std::size_t>> won(chunks);
        tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
            const auto marker = std::int32_t(std::int64_t(INT32_MIN) + std::int64_t(c));
            for (const auto& [q, label] : claims[c]) {
                if (loadRelaxed(id + q) != marker) continue; // an earlier chunk, or an earlier claim here
                __atomic_store_n(id + q, label, __ATOMIC_RELAXED);
                won[c].push_back(q);
            }
            claims[c] = {};
        });
        front.clear();
        for (auto& w : won) front.insert(front.end(), w.begin(), w.end());
    }
}

} // namespace voxhap::segmentation
