// SPDX-License-Identifier: Apache-2.0
/// @file DistanceTransform.cpp
/// @brief Felzenszwalb–Huttenlocher lower envelope, one axis at a time.

#include "segmentation/lattice/DistanceTransform.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>

namespace voxhap::segmentation {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// d[q] = min_p ((q - p)·h)² + f[p]: the lower envelope of the parabolas rooted
/// at the finite samples of f (F&H 2012, algorithm DT(f), with infinite samples skipped).
void envelope1d(const double* f, double* d, double* z, int* v, int n, double h)
{
    int k = -1;
    for (int q = 0; q < n; ++q) {
        if (f[q] == kInf) continue;
        const double fq = f[q] + (q * h) * (q * h);
        double s = -kInf;
        while (k >= 0) {
            const int p = v[k];
            const double fp = f[p] + (p * h) * (p * h);
            s = (fq - fp) / (2.0 * h * h * (q - p)); // intersection, in index units
            if (s <= z[k]) {
                --k;
                s = -kInf;
            } else {
                break;
            }
        }
        ++k;
        v[k] = q;
        z[k] = s;
        z[k + 1] = kInf;
    }
    if (k < 0) {
        for (int q = 0; q < n; ++q) d[q] = kInf;
        return;
    }
    int j = 0;
    for (int q = 0; q < n; ++q) {
        while (z[j + 1] < q) ++j;
        const int p = v[j];
        d[q] = ((q - p) * h) * ((q - p) * h) + f[p];
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
        LineTransform t(n);
        for (std::size_t line = r.begin(); line != r.end(); ++line) {
            const std::size_t u = line % std::size_t(lat.dims[a1]), w = line / std::size_t(lat.dims[a1]);
            t.apply(dist.data() + u * strides[std::size_t(a1)] + w * strides[std::size_t(a2)], step, n, h);
        }
    });
}

} // namespace

LineTransform::LineTransform(int n) : mF(std::size_t(n)), mD(std::size_t(n)), mZ(std::size_t(n) + 1), mV(std::size_t(n))
{
}

void LineTransform::apply(float* data, std::size_t step, int n, double h)
{
    bool any = false;
    for (int q = 0; q < n; ++q) {
        const float x = data[std::size_t(q) * step];
        mF[std::size_t(q)] = std::isinf(x) ? kInf : double(x);
        any = any || !std::isinf(x);
    }
    if (!any) return; // nothing to spread along this line
    envelope1d(mF.data(), mD.data(), mZ.data(), mV.data(), n, h);
    for (int q = 0; q < n; ++q) data[std::size_t(q) * step] = float(mD[std::size_t(q)]);
}

std::vector<float> squaredDistance(const Lattice& lat, const Mask& feature, Span span, bool complement)
{
    std::vector<float> dist(lat.size());
    const float inf = std::numeric_limits<float>::infinity();
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, dist.size(), 1 << 16), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t n = r.begin(); n != r.end(); ++n) dist[n] = (feature[n] != 0) != complement ? 0.0f : inf;
        });
    for (int axis = 0; axis < 3; ++axis) {
        if (span == Span::Slice && axis == lat.sliceAxis) continue;
        if (lat.dims[axis] > 1) passAlong(lat, dist, axis);
    }
    return dist;
}

} // namespace voxhap::segmentation
