// SPDX-License-Identifier: Apache-2.0
/// @file DistanceField.cpp
/// @brief Two distance transforms (to the structure, to its outside) make one signed field.

#include "segmentation/DistanceField.h"

#include "volume/Grids.h"

#include "segmentation/lattice/DenseGrids.h"
#include "segmentation/lattice/DistanceTransform.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace voxhap::segmentation {

std::string distanceFieldName(const std::string& tissue) { return "sdf." + tissue; }

Lattice distanceFieldBox(const Lattice& lat, const std::vector<std::int32_t>& labels, std::int32_t id, double bandMm,
    const std::optional<Lattice>& bounds)
{
    const Lattice& outer = bounds ? *bounds : lat;
    struct Box {
        Vec3i lo{std::numeric_limits<int>::max(), std::numeric_limits<int>::max(), std::numeric_limits<int>::max()};
        Vec3i hi{-1, -1, -1};
    };
    tbb::enumerable_thread_specific<Box> boxes;
    tbb::parallel_for(0, lat.dims.z(), [&](int k) {
        Box& b = boxes.local();
        for (int j = 0; j < lat.dims.y(); ++j) {
            const std::size_t row = lat.index(0, j, k);
            for (int i = 0; i < lat.dims.x(); ++i) {
                if (labels[row + std::size_t(i)] != id) continue;
                b.lo = b.lo.cwiseMin(Vec3i(i, j, k));
                b.hi = b.hi.cwiseMax(Vec3i(i, j, k));
            }
        }
    });
    Box found;
    for (const Box& b : boxes) {
        found.lo = found.lo.cwiseMin(b.lo);
        found.hi = found.hi.cwiseMax(b.hi);
    }
    Lattice box = outer;
    if ((found.hi.array() < found.lo.array()).any()) {
        box.dims = Vec3i::Zero();
        return box;
    }
    for (int a = 0; a < 3; ++a) {
        const int m = int(std::ceil(bandMm / lat.spacing[a])) + 1;
        const int lo = std::max(outer.origin[a], lat.origin[a] + found.lo[a] - m);
        const int hi = std::min(outer.origin[a] + outer.dims[a] - 1, lat.origin[a] + found.hi[a] + m);
        box.origin[a] = lo;
        box.dims[a] = hi - lo + 1;
    }
    return box;
}

volume::Volume::GridPtr signedDistanceField(const Lattice& lat, const std::vector<std::int32_t>& labels,
    std::int32_t id, double bandMm, const std::optional<Lattice>& bounds)
{
    Lattice box = distanceFieldBox(lat, labels, id, bandMm, bounds);
    if (box.size() == 0) box = bounds ? *bounds : lat; // no voxel of the structure: the whole field reads as the band
    // The structure over the box (labels beyond lat are air).
    Mask inside(box.size(), 0);
    const Vec3i off = box.origin - lat.origin;
    tbb::parallel_for(0, box.dims.z(), [&](int k) {
        const int lk = off.z() + k;
        if (lk < 0 || lk >= lat.dims.z()) return;
        for (int j = 0; j < box.dims.y(); ++j) {
            const int lj = off.y() + j;
            if (lj < 0 || lj >= lat.dims.y()) continue;
            for (int i = 0; i < box.dims.x(); ++i) {
                const int li = off.x() + i;
                if (li < 0 || li >= lat.dims.x()) continue;
                inside[box.index(i, j, k)] = labels[lat.index(li, lj, lk)] == id ? 1 : 0;
            }
        }
    });
    std::vector<float> sdf = squaredDistance(box, inside, Span::Volume); // to the inside, then the field
    const std::vector<float> toOutside = squaredDistance(box, inside, Span::Volume, /*complement=*/true);
    // Half the finest spacing: exact in the bound for cubic voxels; on anisotropic
    // ones a surface crossed between slices may be off by up to half the coarser spacing.
    const double half = 0.5 * lat.spacing.minCoeff();
    const auto band = float(bandMm);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, sdf.size(), 1 << 16), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const double d =
                    inside[i] ? -(std::sqrt(double(toOutside[i])) - half) : std::sqrt(double(sdf[i])) - half;
                // No outside voxel in the box (a structure filling it): deep inside.
                sdf[i] = std::isfinite(d) ? std::clamp(float(d), -band, band) : (inside[i] ? -band : band);
            }
        });
    return floatGridFrom(box, sdf, band);
}

} // namespace voxhap::segmentation
