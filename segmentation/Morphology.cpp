// SPDX-License-Identifier: Apache-2.0
/// @file Morphology.cpp
/// @brief Erosion and dilation by thresholding exact distance transforms.

#include "segmentation/Morphology.h"

#include "segmentation/DistanceTransform.h"
#include "segmentation/detail/VoxelLoops.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace voxhap::segmentation {

namespace {

using detail::forEachVoxel;

template <class Op> Mask combine(const Mask& a, const Mask& b, Op op)
{
    Mask out(a.size());
    forEachVoxel(a.size(), [&](std::size_t i) { out[i] = op(a[i], b[i]) ? 1 : 0; });
    return out;
}

} // namespace

Mask erode(const Lattice& lat, const Mask& m, double radiusMm, Span span)
{
    Mask outside(m.size());
    forEachVoxel(m.size(), [&](std::size_t i) { outside[i] = m[i] ? 0 : 1; });
    const std::vector<float> d2 = squaredDistance(lat, outside, span);
    const float r2 = float(radiusMm * radiusMm);
    Mask out(m.size());
    forEachVoxel(m.size(), [&](std::size_t i) { out[i] = (m[i] && d2[i] > r2) ? 1 : 0; });
    return out;
}

Mask dilate(const Lattice& lat, const Mask& m, double radiusMm, Span span)
{
    const std::vector<float> d2 = squaredDistance(lat, m, span);
    const float r2 = float(radiusMm * radiusMm);
    Mask out(m.size());
    forEachVoxel(m.size(), [&](std::size_t i) { out[i] = d2[i] <= r2 ? 1 : 0; });
    return out;
}

Mask close(const Lattice& lat, const Mask& m, double radiusMm, Span span)
{
    return erode(lat, dilate(lat, m, radiusMm, span), radiusMm, span);
}

void fillHolesPerSlice(const Lattice& lat, Mask& m)
{
    const auto [a0, a1] = lat.planeAxes();
    const auto strides = lat.strides();
    const int n0 = lat.dims[a0], n1 = lat.dims[a1];
    const std::size_t s0 = strides[std::size_t(a0)], s1 = strides[std::size_t(a1)];
    const std::size_t ss = strides[std::size_t(lat.sliceAxis)];
    tbb::parallel_for(0, lat.dims[lat.sliceAxis], [&](int k) {
        const std::size_t base = std::size_t(k) * ss;
        // Background reachable from the border: flood fill with an explicit stack.
        std::vector<std::uint8_t> reached(std::size_t(n0) * std::size_t(n1), 0);
        std::vector<std::pair<int, int>> stack;
        auto push = [&](int u, int w) {
            const std::size_t local = std::size_t(u) + std::size_t(n0) * std::size_t(w);
            if (reached[local] || m[base + std::size_t(u) * s0 + std::size_t(w) * s1]) return;
            reached[local] = 1;
            stack.emplace_back(u, w);
        };
        for (int u = 0; u < n0; ++u) {
            push(u, 0);
            push(u, n1 - 1);
        }
        for (int w = 0; w < n1; ++w) {
            push(0, w);
            push(n0 - 1, w);
        }
        while (!stack.empty()) {
            const auto [u, w] = stack.back();
            stack.pop_back();
            if (u > 0) push(u - 1, w);
            if (u + 1 < n0) push(u + 1, w);
            if (w > 0) push(u, w - 1);
            if (w + 1 < n1) push(u, w + 1);
        }
        for (int w = 0; w < n1; ++w) {
            for (int u = 0; u < n0; ++u) {
                if (!reached[std::size_t(u) + std::size_t(n0) * std::size_t(w)]) {
                    m[base + std::size_t(u) * s0 + std::size_t(w) * s1] = 1;
                }
            }
        }
    });
}

std::vector<float> gaussianSmooth(const Lattice& lat, const std::vector<float>& values, double sigmaMm)
{
    std::vector<float> cur = values, next(values.size());
    const auto strides = lat.strides();
    for (int axis = 0; axis < 3; ++axis) {
        const double sigma = sigmaMm / lat.spacing[axis]; // in voxels
        if (sigma < 0.5 || lat.dims[axis] < 2) continue;
        const int radius = int(std::ceil(3.0 * sigma));
        std::vector<double> w(std::size_t(2 * radius + 1));
        double sum = 0;
        for (int t = -radius; t <= radius; ++t)
            sum += w[std::size_t(t + radius)] = std::exp(-0.5 * t * t / (sigma * sigma));
        for (double& x : w) x /= sum;
        const int n = lat.dims[axis];
        const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
        const std::size_t lines = std::size_t(lat.dims[a1]) * std::size_t(lat.dims[a2]);
        const std::size_t step = strides[std::size_t(axis)];
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lines, 64), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t line = r.begin(); line != r.end(); ++line) {
                const std::size_t u = line % std::size_t(lat.dims[a1]), v = line / std::size_t(lat.dims[a1]);
                const std::size_t base = u * strides[std::size_t(a1)] + v * strides[std::size_t(a2)];
                for (int q = 0; q < n; ++q) {
                    double acc = 0;
                    for (int t = -radius; t <= radius; ++t) {
                        const int p = std::clamp(q + t, 0, n - 1);
                        acc += w[std::size_t(t + radius)] * cur[base + std::size_t(p) * step];
                    }
                    next[base + std::size_t(q) * step] = float(acc);
                }
            }
        });
        std::swap(cur, next);
    }
    return cur;
}

Mask maskAnd(const Mask& a, const Mask& b)
{
    return combine(a, b, [](auto x, auto y) { return x && y; });
}
Mask maskAndNot(const Mask& a, const Mask& b)
{
    return combine(a, b, [](auto x, auto y) { return x && !y; });
}
Mask maskOr(const Mask& a, const Mask& b)
{
    return combine(a, b, [](auto x, auto y) { return x || y; });
}

} // namespace voxhap::segmentation
