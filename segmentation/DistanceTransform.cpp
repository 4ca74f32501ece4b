// SPDX-License-Identifier: Apache-2.0
/// @file DistanceTransform.cpp
/// @brief Felzenszwalb–Huttenlocher lower envelope, one axis at a time.

#include "segmentation/DistanceTransform.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>

namespace voxhap::segmentation {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// Working space of one 1-D transform, reused along the lines of a chunk.
struct EnvelopeBuffers {
    std::vector<double> f, d, z;
    std::vector<int> v;
    explicit EnvelopeBuffers(int n) : f(std::size_t(n)), d(std::size_t(n)), z(std::size_t(n) + 1), v(std::size_t(n)) { }
};

/// d[q] = min_p ((q - p)·h)² + f[p]: the lower envelope of the parabolas rooted
/// at the finite samples of f (F&H 2012, algorithm DT(f), with infinite samples skipped).
void envelope1d(EnvelopeBuffers& b, int n, double h)
{
    int k = -1;
    for (int q = 0; q < n; ++q) {
        if (b.f[std::size_t(q)] == kInf) continue;
        const double fq = b.f[std::size_t(q)] + (q * h) * (q * h);
        double s = -kInf;
        while (k >= 0) {
            const int p = b.v[std::size_t(k)];
            const double fp = b.f[std::size_t(p)] + (p * h) * (p * h);
            s = (fq - fp) / (2.0 * h * h * (q - p)); // intersection, in index units
            if (s <= b.z[std::size_t(k)]) {
                --k;
                s = -kInf;
            } else {
                break;
            }
        }
        ++k;
        b.v[std::size_t(k)] = q;
        b.z[std::size_t(k)] = s;
        b.z[std::size_t(k) + 1] = kInf;
    }
    if (k < 0) {
        for (int q = 0; q < n; ++q) b.d[std::size_t(q)] = kInf;
        return;
    }
    int j = 0;
    for (int q = 0; q < n; ++q) {
        while (b.z[std::size_t(j) + 1] < q) ++j;
        const int p = b.v[std::size_t(j)];
        b.d[std::size_t(q)] = ((q - p) * h) * ((q - p) * h) + b.f[std::size_t(p)];
    }
}

/// One pass along @p axis over every line of the lattice.
void passAlong(const Lattice& lat, std::vector<float>& dist, int axis)
{
    const auto strides = lat.strides();
    const int n = lat.dims[axis];
    const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
    const std::size_t lines = std::size_t(lat.dims[a1]) * std::size_t(lat.dims[a2]);
    const std::size_t step = strides[std::size_t(axis)];
    const double h = lat.spacing[axis];
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lines, 64), [&](const tbb::blocked_range<std::size_t>& r) {
        EnvelopeBuffers b(n);
        for (std::size_t line = r.begin(); line != r.end(); ++line) {
            const std::size_t u = line % std::size_t(lat.dims[a1]), w = line / std::size_t(lat.dims[a1]);
            const std::size_t base = u * strides[std::size_t(a1)] + w * strides[std::size_t(a2)];
            bool any = false;
            for (int q = 0; q < n; ++q) {
                const float x = dist[base + std::size_t(q) * step];
                b.f[std::size_t(q)] = std::isinf(x) ? kInf : double(x);
                any = any || !std::isinf(x);
            }
            if (!any) continue; // nothing to spread along this line
            envelope1d(b, n, h);
            for (int q = 0; q < n; ++q) dist[base + std::size_t(q) * step] = float(b.d[std::size_t(q)]);
        }
    });
}

} // namespace

std::vector<float> squaredDistance(const Lattice& lat, const Mask& feature, Span span)
{
    std::vector<float> dist(lat.size());
    const float inf = std::numeric_limits<float>::infinity();
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, dist.size(), 1 << 16), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t n = r.begin(); n != r.end(); ++n) dist[n] = feature[n] ? 0.0f : inf;
        });
    for (int axis = 0; axis < 3; ++axis) {
        if (span == Span::Slice && axis == lat.sliceAxis) continue;
        if (lat.dims[axis] > 1) passAlong(lat, dist, axis);
    }
    return dist;
}

} // namespace voxhap::segmentation
