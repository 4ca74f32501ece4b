// SPDX-License-Identifier: Apache-2.0
/// @file Morphology.cpp
/// @brief Erosion and dilation by thresholding exact distance transforms.

#include "segmentation/lattice/Morphology.h"

#include "segmentation/detail/VoxelLoops.h"
#include "segmentation/lattice/DistanceTransform.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace voxhap::segmentation {

namespace {

using detail::forEachVoxel;

template <class Op> Mask combine(const Mask& a, const Mask& b, Op op)
{
    Mask out(a.size());
    forEachVoxel(a.size(), [&](std::size_t i) { out[i] = op(a[i], b[i]) ? 1 : 0; });
    return out;
}

constexpr float kInfF = std::numeric_limits<float>::infinity();

/// One slice's two in-plane axes: a0 (u, fastest in the local buffer) and a1 (w).
struct SliceAxes {
    int a0, a1, n0, n1;
    std::size_t s0, s1, ss;
    explicit SliceAxes(const Lattice& lat)
    {
        const auto axes = lat.planeAxes();
        const auto strides = lat.strides();
        a0 = axes[0], a1 = axes[1];
        n0 = lat.dims[a0], n1 = lat.dims[a1];
        s0 = strides[std::size_t(a0)], s1 = strides[std::size_t(a1)];
        ss = strides[std::size_t(lat.sliceAxis)];
    }
    std::size_t element(int slice, int u, int w) const
    {
        return std::size_t(slice) * ss + std::size_t(u) * s0 + std::size_t(w) * s1;
    }
};

/// In-plane squared distances of a slice buffer holding 0 at features and +inf
/// elsewhere: the passes of squaredDistance(Span::Slice), in its axis order.
void sliceDistance(
    const Lattice& lat, const SliceAxes& g, std::vector<float>& buf, LineTransform& t0, LineTransform& t1)
{
    if (lat.dims[g.a0] > 1)
        for (int w = 0; w < g.n1; ++w)
            t0.apply(buf.data() + std::size_t(w) * std::size_t(g.n0), 1, g.n0, lat.spacing[g.a0]);
    if (lat.dims[g.a1] > 1)
        for (int u = 0; u < g.n0; ++u) t1.apply(buf.data() + u, std::size_t(g.n0), g.n1, lat.spacing[g.a1]);
}

/// out = keep(inMask, d2) per slice, where d2 is the in-plane squared distance to
/// the voxels where feature(inMask) holds; @p twice applies a second such step
/// to the first's result (a closing) without leaving the slice.
template <class Feature, class Keep>
Mask perSlice(const Lattice& lat, const Mask& m, Feature feature, Keep keep, bool twice = false,
    std::function<bool(bool)> feature2 = {}, std::function<bool(bool, float)> keep2 = {})
{
    const SliceAxes g(lat);
    Mask out(m.size());
    tbb::parallel_for(0, lat.dims[lat.sliceAxis], [&](int k) {
        const std::size_t plane = std::size_t(g.n0) * std::size_t(g.n1);
        std::vector<float> buf(plane);
        std::vector<std::uint8_t> cur(plane);
        LineTransform t0(g.n0), t1(g.n1);
        for (int w = 0; w < g.n1; ++w)
            for (int u = 0; u < g.n0; ++u)
                cur[std::size_t(u) + std::size_t(g.n0) * std::size_t(w)] = m[g.element(k, u, w)];
        for (std::size_t n = 0; n < plane; ++n) buf[n] = feature(cur[n] != 0) ? 0.0f : kInfF;
        sliceDistance(lat, g, buf, t0, t1);
        for (std::size_t n = 0; n < plane; ++n) cur[n] = keep(cur[n] != 0, buf[n]) ? 1 : 0;
        if (twice) {
            for (std::size_t n = 0; n < plane; ++n) buf[n] = feature2(cur[n] != 0) ? 0.0f : kInfF;
            sliceDistance(lat, g, buf, t0, t1);
            for (std::size_t n = 0; n < plane; ++n) cur[n] = keep2(cur[n] != 0, buf[n]) ? 1 : 0;
        }
        for (int w = 0; w < g.n1; ++w)
            for (int u = 0; u < g.n0; ++u)
                out[g.element(k, u, w)] = cur[std::size_t(u) + std::size_t(g.n0) * std::size_t(w)];
    });
    return out;
}

/// The 3-D threshold test in slabs of k planes. The whole-lattice transform's
/// last pass (along k) is min over p of ((k − p)·h)² + f[p], f the in-plane
/// result; with the threshold r², planes with |k − p|·h > r add nothing, so a
/// window of floor(r/h) + 1 planes each side gives the same decision.
template <class Feature, class Keep>
Mask perSlab(const Lattice& lat, const Mask& m, double radiusMm, Feature feature, Keep keep)
{
    const int nx = lat.dims.x(), ny = lat.dims.y(), nz = lat.dims.z();
    const std::size_t plane = std::size_t(nx) * std::size_t(ny);
    const double hz = lat.spacing.z();
    const int reach = nz > 1 ? int(std::floor(radiusMm / hz)) + 1 : 0;
    constexpr int kSlab = 8;
    Mask out(m.size());
    tbb::parallel_for(0, (nz + kSlab - 1) / kSlab, [&](int s) {
        const int k0 = s * kSlab, k1 = std::min(nz, k0 + kSlab);
        const int h0 = std::max(0, k0 - reach), h1 = std::min(nz, k1 + reach);
        std::vector<float> buf(plane * std::size_t(h1 - h0));
        LineTransform tx(nx), ty(ny);
        for (int k = h0; k < h1; ++k) {
            float* p = buf.data() + plane * std::size_t(k - h0);
            const std::uint8_t* src = m.data() + plane * std::size_t(k);
            for (std::size_t n = 0; n < plane; ++n) p[n] = feature(src[n] != 0) ? 0.0f : kInfF;
            if (nx > 1)
                for (int j = 0; j < ny; ++j) tx.apply(p + std::size_t(j) * std::size_t(nx), 1, nx, lat.spacing.x());
            if (ny > 1)
                for (int i = 0; i < nx; ++i) ty.apply(p + i, std::size_t(nx), ny, lat.spacing.y());
        }
        for (int k = k0; k < k1; ++k) {
            const int lo = std::max(h0, k - reach), hi = std::min(h1 - 1, k + reach);
            for (std::size_t n = 0; n < plane; ++n) {
                double best = std::numeric_limits<double>::infinity();
                for (int q = lo; q <= hi; ++q) {
                    const float f = buf[plane * std::size_t(q - h0) + n];
                    if (std::isinf(f)) continue;
                    const double d = ((k - q) * hz) * ((k - q) * hz) + double(f);
                    best = std::min(best, d);
                }
                const std::size_t e = plane * std::size_t(k) + n;
                out[e] = keep(m[e] != 0, float(best)) ? 1 : 0;
            }
        }
    });
    return out;
}

} // namespace

Mask erode(const Lattice& lat, const Mask& m, double radiusMm, Span span)
{
    const float r2 = float(radiusMm * radiusMm);
    const auto feature = [](bool in) { return !in; };
    const auto keep = [r2](bool in, float d2) { return in && d2 > r2; };
    return span == Span::Slice ? perSlice(lat, m, feature, keep) : perSlab(lat, m, radiusMm, feature, keep);
}

Mask dilate(const Lattice& lat, const Mask& m, double radiusMm, Span span)
{
    const float r2 = float(radiusMm * radiusMm);
    const auto feature = [](bool in) { return in; };
    const auto keep = [r2](bool, float d2) { return d2 <= r2; };
    return span == Span::Slice ? perSlice(lat, m, feature, keep) : perSlab(lat, m, radiusMm, feature, keep);
}

Mask innerShell(const Lattice& lat, const Mask& m, double radiusMm)
{
    const float r2 = float(radiusMm * radiusMm);
    return perSlice(
        lat, m, [](bool in) { return !in; }, [r2](bool in, float d2) { return in && d2 < r2; });
}

Mask close(const Lattice& lat, const Mask& m, double radiusMm, Span span)
{
    if (span == Span::Volume) return erode(lat, dilate(lat, m, radiusMm, span), radiusMm, span);
    const float r2 = float(radiusMm * radiusMm);
    return perSlice(
        lat, m, [](bool in) { return in; }, [r2](bool, float d2) { return d2 <= r2; }, true,
        [](bool in) { return !in; }, [r2](bool in, float d2) { return in && d2 > r2; });
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
        // Background reachable from the border: a scanline flood fill. Each seed
        // grows into its whole run along a0, and one seed is pushed per run of
        // open pixels in the rows beside it, so a slice costs a few stack
        // operations per run rather than four per pixel (a CT slice is mostly
        // one background region; the pixel-by-pixel fill was 16 % of `voxhap
        // plan`'s CPU time on the shared CT).
        std::vector<std::uint8_t> reached(std::size_t(n0) * std::size_t(n1), 0);
        const auto open = [&](int u, int w) {
            return !reached[std::size_t(u) + std::size_t(n0) * std::size_t(w)] &&
                !m[base + std::size_t(u) * s0 + std::size_t(w) * s1];
        };
        std::vector<std::pair<int, int>> stack;
        // One seed per run of open pixels in row w between u0 and u1.
        const auto seedRuns = [&](int u0, int u1, int w) {
            bool inRun = false;
            for (int u = u0; u <= u1; ++u) {
                const bool o = open(u, w);
                if (o && !inRun) stack.emplace_back(u, w);
                inRun = o;
            }
        };
        seedRuns(0, n0 - 1, 0);
        seedRuns(0, n0 - 1, n1 - 1);
        for (int w = 1; w + 1 < n1; ++w) {
            if (open(0, w)) stack.emplace_back(0, w);
            if (open(n0 - 1, w)) stack.emplace_back(n0 - 1, w);
        }
        while (!stack.empty()) {
            const auto [u, w] = stack.back();
            stack.pop_back();
            if (!open(u, w)) continue; // reached through another seed meanwhile
            int lo = u, hi = u;
            while (lo > 0 && open(lo - 1, w)) --lo;
            while (hi + 1 < n0 && open(hi + 1, w)) ++hi;
            std::fill_n(reached.begin() + std::ptrdiff_t(std::size_t(lo) + std::size_t(n0) * std::size_t(w)),
                hi - lo + 1, std::uint8_t(1));
            if (w > 0) seedRuns(lo, hi, w - 1);
            if (w + 1 < n1) seedRuns(lo, hi, w + 1);
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

namespace {

/// The normalised kernel of gaussianSmooth() along @p axis; empty if that axis is left alone.
std::vector<double> kernel(const Lattice& lat, double sigmaMm, int axis)
{
    const double sigma = sigmaMm / lat.spacing[axis]; // in voxels
    if (sigma < 0.5 || lat.dims[axis] < 2) return {};
    const int radius = int(std::ceil(3.0 * sigma));
    std::vector<double> w(std::size_t(2 * radius + 1));
    double sum = 0;
    for (int t = -radius; t <= radius; ++t)
        sum += w[std::size_t(t + radius)] = std::exp(-0.5 * t * t / (sigma * sigma));
    for (double& x : w) x /= sum;
    return w;
}

/// One line: dst[q·step] = Σ w[t]·src[clamp(q + t)·step], accumulated in double.
void smoothLine(const float* src, float* dst, std::size_t step, int n, const std::vector<double>& w)
{
    const int radius = int(w.size() / 2);
    for (int q = 0; q < n; ++q) {
        double acc = 0;
        for (int t = -radius; t <= radius; ++t) {
            const int p = std::clamp(q + t, 0, n - 1);
            acc += w[std::size_t(t + radius)] * src[std::size_t(p) * step];
        }
        dst[std::size_t(q) * step] = float(acc);
    }
}

} // namespace

void gaussianSmoothPlanes(const Lattice& lat, double sigmaMm,
    const std::function<void(int k0, int k1, float* out)>& read,
    const std::function<void(int k, const float* plane)>& sink)
{
    const int nx = lat.dims.x(), ny = lat.dims.y(), nz = lat.dims.z();
    const std::size_t plane = std::size_t(nx) * std::size_t(ny);
    if (plane == 0 || nz == 0) return;
    const std::vector<double> wx = kernel(lat, sigmaMm, 0), wy = kernel(lat, sigmaMm, 1), wz = kernel(lat, sigmaMm, 2);
    const int reach = int(wz.size() / 2); // planes each side the k pass reads
    // Passes along i, then j, then k, each rounded to float as gaussianSmooth()
    // always did: a plane's i and j passes need only that plane.
    constexpr int kSlab = 8;
    tbb::parallel_for(0, (nz + kSlab - 1) / kSlab, [&](int s) {
        const int k0 = s * kSlab, k1 = std::min(nz, k0 + kSlab);
        const int h0 = std::max(0, k0 - reach), h1 = std::min(nz, k1 + reach);
        std::vector<float> buf(plane * std::size_t(h1 - h0)), tmp(plane);
        read(h0, h1, buf.data());
        for (int k = h0; k < h1; ++k) {
            float* p = buf.data() + plane * std::size_t(k - h0);
            if (!wx.empty()) {
                for (int j = 0; j < ny; ++j)
                    smoothLine(
                        p + std::size_t(j) * std::size_t(nx), tmp.data() + std::size_t(j) * std::size_t(nx), 1, nx, wx);
                std::copy(tmp.begin(), tmp.end(), p);
            }
            if (!wy.empty()) {
                for (int i = 0; i < nx; ++i) smoothLine(p + i, tmp.data() + i, std::size_t(nx), ny, wy);
                std::copy(tmp.begin(), tmp.end(), p);
            }
        }
        for (int k = k0; k < k1; ++k) {
            if (wz.empty()) {
                sink(k, buf.data() + plane * std::size_t(k - h0));
                continue;
            }
            for (std::size_t n = 0; n < plane; ++n) {
                double acc = 0;
                for (int t = -reach; t <= reach; ++t) {
                    const int p = std::clamp(k + t, 0, nz - 1);
                    acc += wz[std::size_t(t + reach)] * buf[plane * std::size_t(p - h0) + n];
                }
                tmp[n] = float(acc);
            }
            sink(k, tmp.data());
        }
    });
}

std::vector<float> gaussianSmooth(const Lattice& lat, const std::vector<float>& values, double sigmaMm)
{
    std::vector<float> out(values.size());
    const std::size_t plane = std::size_t(lat.dims.x()) * std::size_t(lat.dims.y());
    gaussianSmoothPlanes(
        lat, sigmaMm,
        [&](int k0, int k1, float* buf) {
            std::copy(values.begin() + std::ptrdiff_t(plane * std::size_t(k0)),
                values.begin() + std::ptrdiff_t(plane * std::size_t(k1)), buf);
        },
        [&](int k, const float* p) { std::copy(p, p + plane, out.begin() + std::ptrdiff_t(plane * std::size_t(k))); });
    return out;
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
