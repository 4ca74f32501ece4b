// SPDX-License-Identifier: Apache-2.0
/// @file LevelImage.cpp
/// @brief Block averages of a sparse channel and of a dense level.

#include "registration/LevelImage.h"

#include "core/Errors.h"
#include "volume/Grids.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace voxhap::registration {

using volume::Channel;
using volume::FloatGrid;

namespace {

/// Sums and active counts per output voxel.
struct Accumulator {
    explicit Accumulator(std::size_t n) : sum(n, 0.0), active(n, 0) { }
    std::vector<double> sum;
    std::vector<std::uint32_t> active;
};

/// The level lattice of @p factors over a source geometry whose box starts at @p min.
volume::Geometry levelGeometry(const volume::Geometry& g, const Vec3d& firstCentre, const Vec3i& factors)
{
    volume::Geometry out = g;
    out.spacing = g.spacing.cwiseProduct(factors.cast<double>());
    const Vec3d centre = firstCentre + 0.5 * (factors.cast<double>() - Vec3d::Ones());
    out.origin = g.origin + g.direction * g.spacing.cwiseProduct(centre);
    return out;
}

/// Visit each active voxel of the row (y, z) from @p xBegin to before @p xEnd
/// in x order, with its value: a leaf at a time, an active tile's value once
/// per voxel it covers.
template <typename Accessor, typename Visit>
void forEachActiveInRow(Accessor& acc, int y, int z, int xBegin, int xEnd, Visit visit)
{
    using Leaf = FloatGrid::TreeType::LeafNodeType;
    constexpr int kLeafDim = int(Leaf::DIM);
    for (int x = xBegin; x < xEnd;) {
        const int segmentEnd = std::min(xEnd, (x & ~(kLeafDim - 1)) + kLeafDim);
        if (const Leaf* leaf = acc.probeConstLeaf(openvdb::Coord(x, y, z))) {
            for (int xx = x; xx < segmentEnd; ++xx) {
                const auto offset = Leaf::coordToOffset(openvdb::Coord(xx, y, z));
                if (leaf->isValueOn(offset)) visit(xx, leaf->getValue(offset));
            }
        } else if (float value; acc.probeValue(openvdb::Coord(x, y, z), value)) {
            for (int xx = x; xx < segmentEnd; ++xx) visit(xx, value); // an active tile
        }
        x = segmentEnd;
    }
}

LevelImage finish(LevelImage out, const Accumulator& acc, std::uint32_t blockVoxels, float background)
{
    const std::size_t n = acc.sum.size();
    out.values.resize(n);
    out.body.resize(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const double air = double(blockVoxels - acc.active[i]) * double(background);
            out.values[i] = float((acc.sum[i] + air) / double(blockVoxels));
            out.body[i] = 2 * acc.active[i] >= blockVoxels ? 1 : 0;
        }
    });
    return out;
}

} // namespace

float backgroundOf(Channel c)
{
    switch (c) {
    case Channel::Hu:
        return volume::kAirHu;
    case Channel::T1:
        return volume::kAirT1;
    case Channel::Intensity:
        return volume::kAirIntensity;
    case Channel::Label:
        break;
    }
    throw ValueError("registration: the label channel is not an image (labels are not interpolated)");
}

bool LevelImage::inside(const Vec3d& w) const
{
    const Vec3d ijk = toIndex(w);
    for (int a = 0; a < 3; ++a) {
        if (!(ijk[a] >= -0.5 && ijk[a] <= double(dims[a]) - 0.5)) return false;
    }
    return true;
}

std::int64_t LevelImage::bodyCount() const
{
    return std::int64_t(std::count(body.begin(), body.end(), std::uint8_t(1)));
}

Vec3d LevelImage::bodyCentroid() const
{
    Vec3d sum = Vec3d::Zero();
    std::int64_t n = 0;
    for (int k = 0; k < dims.z(); ++k) {
        for (int j = 0; j < dims.y(); ++j) {
            for (int i = 0; i < dims.x(); ++i) {
                if (!body[std::size_t(index(i, j, k))]) continue;
                sum += Vec3d(i, j, k);
                ++n;
            }
        }
    }
    return n ? world(sum / double(n)) : world(0.5 * (dims.cast<double>() - Vec3d::Ones()));
}

Vec3i blockFactors(const Vec3d& spacing, double targetMm)
{
    Vec3i f;
    for (int a = 0; a < 3; ++a) f[a] = std::max(1, int(std::lround(targetMm / spacing[a])));
    return f;
}

LevelImage blockAverage(const volume::Volume& v, Channel c, const Vec3i& factors)
{
    volume::initializeOpenVdb();
    const float background = backgroundOf(c);
    const auto grid = openvdb::gridConstPtrCast<FloatGrid>(v.grid(c));
    if (!grid) throw ValueError("registration: the volume has no " + std::string(volume::channelName(c)) + " grid");
    const volume::IndexBox box = v.indexBox();
    LevelImage out;
    out.dims = box.dims().cwiseQuotient(factors);
    if ((out.dims.array() < 1).any()) {
        throw ValueError("registration: the volume (" + std::to_string(box.dims().x()) + " x " +
            std::to_string(box.dims().y()) + " x " + std::to_string(box.dims().z()) +
            " voxels) is smaller than one block of the registration's coarsest level");
    }
    out.geometry = levelGeometry(v.geometry(), box.min.cast<double>(), factors);
    const std::size_t n = std::size_t(out.count());
    const Vec3i last = box.min + out.dims.cwiseProduct(factors) - Vec3i::Ones(); // inclusive, full blocks only

    // Each output slab gathers its blocks through its own accessor: a fixed
    // summing order (the same answer every run) and no per-thread copies of
    // the level, which at the finest level would cost more than the level.
    // A source row is read a leaf at a time (a tile's value once), and each
    // block still sums its voxels z, then y, then x first.
    const int xEnd = last.x() + 1;
    if (factors == Vec3i::Ones()) {
        // Blocks of one voxel: each value is its voxel's (a float through a
        // double and back is itself), the air's where it is inactive. No sums.
        out.values.assign(n, background);
        out.body.assign(n, 0);
        tbb::parallel_for(tbb::blocked_range<int>(0, out.dims.z()), [&](const tbb::blocked_range<int>& ks) {
            auto acc = grid->getConstAccessor();
            for (int k = ks.begin(); k != ks.end(); ++k) {
                for (int j = 0; j < out.dims.y(); ++j) {
                    const auto row = std::size_t(out.index(0, j, k));
                    forEachActiveInRow(
                        acc, box.min.y() + j, box.min.z() + k, box.min.x(), xEnd, [&](int x, float value) {
                            const std::size_t at = row + std::size_t(x - box.min.x());
                            out.values[at] = value;
                            out.body[at] = 1;
                        });
                }
            }
        });
        return out;
    }
    Accumulator total(n);
    tbb::parallel_for(tbb::blocked_range<int>(0, out.dims.z()), [&](const tbb::blocked_range<int>& ks) {
        auto acc = grid->getConstAccessor();
        std::vector<double> rowSum(std::size_t(out.dims.x()));
        std::vector<std::uint32_t> rowActive(std::size_t(out.dims.x()));
        for (int k = ks.begin(); k != ks.end(); ++k) {
            for (int j = 0; j < out.dims.y(); ++j) {
                std::fill(rowSum.begin(), rowSum.end(), 0.0);
                std::fill(rowActive.begin(), rowActive.end(), 0u);
                for (int dz = 0; dz < factors.z(); ++dz) {
                    for (int dy = 0; dy < factors.y(); ++dy) {
                        const int y = box.min.y() + j * factors.y() + dy, z = box.min.z() + k * factors.z() + dz;
                        forEachActiveInRow(acc, y, z, box.min.x(), xEnd, [&](int x, float value) {
                            const auto cell = std::size_t((x - box.min.x()) / factors.x());
                            rowSum[cell] += double(value);
                            ++rowActive[cell];
                        });
                    }
                }
                const auto row = std::size_t(out.index(0, j, k));
                std::copy(rowSum.begin(), rowSum.end(), total.sum.begin() + std::ptrdiff_t(row));
                std::copy(rowActive.begin(), rowActive.end(), total.active.begin() + std::ptrdiff_t(row));
            }
        }
    });
    return finish(std::move(out), total, std::uint32_t(factors.prod()), background);
}

LevelImage blockAverage(const LevelImage& fine, const Vec3i& factors)
{
    LevelImage out;
    out.dims = fine.dims.cwiseQuotient(factors).cwiseMax(Vec3i::Ones());
    const Vec3i f = factors.cwiseMin(fine.dims);
    out.geometry = levelGeometry(fine.geometry, Vec3d::Zero(), f);
    const std::size_t n = std::size_t(out.count());
    out.values.assign(n, 0.0f);
    out.body.assign(n, 0);
    const double blockVoxels = double(f.prod());
    tbb::parallel_for(0, out.dims.z(), [&](int k) {
        for (int j = 0; j < out.dims.y(); ++j) {
            for (int i = 0; i < out.dims.x(); ++i) {
                double sum = 0.0;
                int body = 0;
                for (int c = 0; c < f.z(); ++c) {
                    for (int b = 0; b < f.y(); ++b) {
                        for (int a = 0; a < f.x(); ++a) {
                            const std::size_t s = std::size_t(fine.index(i * f.x() + a, j * f.y() + b, k * f.z() + c));
                            sum += double(fine.values[s]);
                            body += fine.body[s];
                        }
                    }
                }
                const std::size_t o = std::size_t(out.index(i, j, k));
                out.values[o] = float(sum / blockVoxels);
                out.body[o] = 2 * body >= int(blockVoxels) ? 1 : 0;
            }
        }
    });
    return out;
}

namespace {

/// One pass of 6-neighbour erosion (grow = false), or of dilation within @p limit.
/// Row by row, so that a voxel's neighbours are offsets, not divisions; a
/// neighbour outside the image neither erodes nor grows (a row of ones or of
/// zeros stands in for it). Within a row the voxels between the first and the
/// last are the same sum of bytes, without branches, so the compiler runs them
/// as vectors: a tenth of a torso's registration went to these passes.
std::vector<std::uint8_t> morphologyPass(
    const std::vector<std::uint8_t>& in, const Vec3i& d, bool grow, const std::vector<std::uint8_t>* limit)
{
    std::vector<std::uint8_t> out(in.size());
    const std::int64_t nx = d.x(), nxy = std::int64_t(d.x()) * d.y();
    const std::vector<std::uint8_t> outside(std::size_t(nx), grow ? 0 : 1);
    tbb::parallel_for(tbb::blocked_range<int>(0, d.z()), [&](const tbb::blocked_range<int>& ks) {
        for (int k = ks.begin(); k != ks.end(); ++k) {
            for (int j = 0; j < d.y(); ++j) {
                const std::int64_t row = k * nxy + j * nx;
                const std::uint8_t* c = in.data() + row;
                const std::uint8_t* yl = j > 0 ? c - nx : outside.data();
                const std::uint8_t* yh = j + 1 < d.y() ? c + nx : outside.data();
                const std::uint8_t* zl = k > 0 ? c - nxy : outside.data();
                const std::uint8_t* zh = k + 1 < d.z() ? c + nxy : outside.data();
                const std::uint8_t* lim = limit ? limit->data() + row : nullptr;
                std::uint8_t* o = out.data() + row;
                // The voxel at x = i, its x neighbours read as `left` and `right`.
                const auto one = [&](std::int64_t i, std::uint8_t left, std::uint8_t right) {
                    if (grow) {
                        const bool any = (left | right | yl[i] | yh[i] | zl[i] | zh[i]) != 0;
                        o[i] = std::uint8_t(c[i] != 0 || (any && (!lim || lim[i] != 0)));
                    } else {
                        o[i] = std::uint8_t(c[i] != 0 && left != 0 && right != 0 && yl[i] != 0 && yh[i] != 0 &&
                            zl[i] != 0 && zh[i] != 0);
                    }
                };
                const std::uint8_t edge = outside[0];
                if (nx == 1) {
                    one(0, edge, edge);
                    continue;
                }
                one(0, edge, c[1]);
                if (grow && lim) {
                    for (std::int64_t i = 1; i + 1 < nx; ++i) {
                        const std::uint8_t any = c[i - 1] | c[i + 1] | yl[i] | yh[i] | zl[i] | zh[i];
                        o[i] = std::uint8_t((c[i] != 0) | ((any != 0) & (lim[i] != 0)));
                    }
                } else if (grow) {
                    for (std::int64_t i = 1; i + 1 < nx; ++i) {
                        o[i] = std::uint8_t((c[i] | c[i - 1] | c[i + 1] | yl[i] | yh[i] | zl[i] | zh[i]) != 0);
                    }
                } else {
                    for (std::int64_t i = 1; i + 1 < nx; ++i) {
                        o[i] = std::uint8_t((c[i] != 0) & (c[i - 1] != 0) & (c[i + 1] != 0) & (yl[i] != 0) &
                            (yh[i] != 0) & (zl[i] != 0) & (zh[i] != 0));
                    }
                }
                one(nx - 1, c[nx - 2], edge);
            }
        }
    });
    return out;
}

/// The runs along x of the voxels where @p in holds, row by row (row r = k·ny + j),
/// and their 6-connected parts: each run joined to the runs it overlaps in x in
/// the row before (j − 1) and the slice before (k − 1). The same parts as a
/// flood's, in O(voxels + runs) without a division per voxel.
struct RunParts {
    std::vector<std::int32_t> begin, end; ///< [begin, end) along x
    std::vector<std::int64_t> rowFirst;   ///< the first run of each row; one more for the end
    std::vector<std::int32_t> parent;     ///< union-find over the runs

    std::int32_t root(std::int32_t r)
    {
        while (parent[std::size_t(r)] != r) {
            parent[std::size_t(r)] = parent[std::size_t(parent[std::size_t(r)])];
            r = parent[std::size_t(r)];
        }
        return r;
    }
    void join(std::int32_t a, std::int32_t b)
    {
        a = root(a), b = root(b);
        if (a != b) parent[std::size_t(std::max(a, b))] = std::min(a, b); // the earlier run is the root
    }
    /// Join the runs of row @p r to the overlapping runs of row @p s.
    void joinRows(std::int64_t r, std::int64_t s)
    {
        std::int64_t a = rowFirst[std::size_t(r)], b = rowFirst[std::size_t(s)];
        const std::int64_t aEnd = rowFirst[std::size_t(r) + 1], bEnd = rowFirst[std::size_t(s) + 1];
        while (a < aEnd && b < bEnd) {
            if (begin[std::size_t(a)] < end[std::size_t(b)] && begin[std::size_t(b)] < end[std::size_t(a)])
                join(std::int32_t(a), std::int32_t(b));
            if (end[std::size_t(a)] < end[std::size_t(b)])
                ++a;
            else
                ++b;
        }
    }
};

template <typename In> RunParts runParts(const Vec3i& d, In&& in)
{
    RunParts p;
    const std::int64_t rows = std::int64_t(d.y()) * d.z();
    p.rowFirst.reserve(std::size_t(rows) + 1);
    for (std::int64_t r = 0; r < rows; ++r) {
        p.rowFirst.push_back(std::int64_t(p.begin.size()));
        const std::int64_t row = r * d.x();
        for (int i = 0; i < d.x();) {
            if (!in(std::size_t(row + i))) {
                ++i;
                continue;
            }
            const int from = i;
            while (i < d.x() && in(std::size_t(row + i))) ++i;
            p.begin.push_back(from);
            p.end.push_back(i);
        }
    }
    p.rowFirst.push_back(std::int64_t(p.begin.size()));
    p.parent.resize(p.begin.size());
    for (std::size_t q = 0; q < p.parent.size(); ++q) p.parent[q] = std::int32_t(q);
    for (std::int64_t r = 0; r < rows; ++r) {
        const std::int64_t j = r % d.y();
        if (j > 0) p.joinRows(r, r - 1);
        if (r >= d.y()) p.joinRows(r, r - d.y());
    }
    return p;
}

} // namespace

void bodyAbove(LevelImage& image, float threshold, int openingVoxels)
{
    const Vec3i d = image.dims;
    const std::size_t n = image.values.size();
    std::vector<std::uint8_t> mask(n);
    for (std::size_t q = 0; q < n; ++q) mask[q] = image.values[q] > threshold ? 1 : 0;
    // Opened: erosion cuts what joins the body only through thin parts (a
    // table top, a box's lid and walls), and dilation within the mask gives
    // the part kept back its skin.
    std::vector<std::uint8_t> core = mask;
    for (int p = 0; p < openingVoxels; ++p) core = morphologyPass(core, d, false, nullptr);
    // The parts of the core; the largest is the body (on a tie the one met first
    // in scan order: a run's root is its part's first run).
    RunParts parts = runParts(d, [&](std::size_t q) { return core[q] != 0; });
    const auto runs = std::int32_t(parts.begin.size());
    std::vector<std::int64_t> size(parts.begin.size(), 0);
    for (std::int32_t r = 0; r < runs; ++r)
        size[std::size_t(parts.root(r))] += parts.end[std::size_t(r)] - parts.begin[std::size_t(r)];
    std::int32_t best = -1;
    std::int64_t bestSize = 0;
    for (std::int32_t r = 0; r < runs; ++r) {
        if (parts.parent[std::size_t(r)] == r && size[std::size_t(r)] > bestSize)
            best = r, bestSize = size[std::size_t(r)];
    }
    const std::int64_t rows = std::int64_t(d.y()) * d.z();
    std::vector<std::uint8_t> body(n, 0);
    for (std::int64_t row = 0; row < rows; ++row) {
        for (std::int64_t r = parts.rowFirst[std::size_t(row)]; r < parts.rowFirst[std::size_t(row) + 1]; ++r) {
            if (parts.root(std::int32_t(r)) != best) continue;
            const auto at = std::size_t(row * d.x());
            std::fill(body.begin() + std::ptrdiff_t(at + std::size_t(parts.begin[std::size_t(r)])),
                body.begin() + std::ptrdiff_t(at + std::size_t(parts.end[std::size_t(r)])), std::uint8_t(1));
        }
    }
    for (int p = 0; p < openingVoxels; ++p) body = morphologyPass(body, d, true, &mask);
    // Its holes filled: what the border cannot reach through the rest is
    // inside (gas, marrow, a dark cyst), so that the body's surface is its skin.
    // The rest's parts that touch the image's border are outside.
    RunParts gaps = runParts(d, [&](std::size_t q) { return body[q] == 0; });
    std::vector<std::uint8_t> outside(gaps.begin.size(), 0);
    for (std::int64_t row = 0; row < rows; ++row) {
        const std::int64_t j = row % d.y(), k = row / d.y();
        const bool edgeRow = j == 0 || k == 0 || j == d.y() - 1 || k == d.z() - 1;
        for (std::int64_t r = gaps.rowFirst[std::size_t(row)]; r < gaps.rowFirst[std::size_t(row) + 1]; ++r) {
            if (edgeRow || gaps.begin[std::size_t(r)] == 0 || gaps.end[std::size_t(r)] == d.x())
                outside[std::size_t(gaps.root(std::int32_t(r)))] = 1;
        }
    }
    std::fill(image.body.begin(), image.body.end(), std::uint8_t(best >= 0 ? 1 : 0));
    if (best < 0) return;
    for (std::int64_t row = 0; row < rows; ++row) {
        for (std::int64_t r = gaps.rowFirst[std::size_t(row)]; r < gaps.rowFirst[std::size_t(row) + 1]; ++r) {
            if (!outside[std::size_t(gaps.root(std::int32_t(r)))]) continue;
            const auto at = std::size_t(row * d.x());
            std::fill(image.body.begin() + std::ptrdiff_t(at + std::size_t(gaps.begin[std::size_t(r)])),
                image.body.begin() + std::ptrdiff_t(at + std::size_t(gaps.end[std::size_t(r)])), std::uint8_t(0));
        }
    }
}

std::vector<std::uint8_t> grownBody(const LevelImage& image, int passes)
{
    std::vector<std::uint8_t> body = image.body;
    for (int p = 0; p < passes; ++p) body = morphologyPass(body, image.dims, true, nullptr);
    return body;
}

void clampValues(LevelImage& image, float lo, float hi)
{
    for (float& v : image.values) v = std::clamp(v, lo, hi);
}

float bodyQuantile(const LevelImage& image, double fraction) { return bodyQuantiles(image, {fraction}).front(); }

std::vector<float> bodyQuantiles(const LevelImage& image, const std::vector<double>& fractions)
{
    std::vector<float> values;
    values.reserve(std::size_t(image.bodyCount()));
    for (std::size_t i = 0; i < image.values.size(); ++i) {
        if (image.body[i]) values.push_back(image.values[i]);
    }
    std::vector<float> out(fractions.size(), 0.0f);
    if (values.empty()) return out;
    // Highest fraction first: each selection leaves the values below it in
    // front, so the next one searches only those.
    std::vector<std::size_t> order(fractions.size());
    std::iota(order.begin(), order.end(), std::size_t(0));
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return fractions[a] > fractions[b]; });
    auto end = values.end();
    for (std::size_t q : order) {
        const auto at = values.begin() + std::ptrdiff_t(std::clamp(fractions[q], 0.0, 1.0) * double(values.size() - 1));
        std::nth_element(values.begin(), at, end);
        out[q] = *at;
        end = at + 1;
    }
    return out;
}

} // namespace voxhap::registration
