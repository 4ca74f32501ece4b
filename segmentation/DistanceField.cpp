// SPDX-License-Identifier: Apache-2.0
/// @file DistanceField.cpp
/// @brief Two distance transforms (to the structure, to its outside) make one signed field.

#include "segmentation/DistanceField.h"

#include "volume/Grids.h"

#include "segmentation/DenseGrids.h"
#include "segmentation/DistanceTransform.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace voxhap::segmentation {

std::string distanceFieldName(const std::string& tissue) { return "sdf." + tissue; }

volume::Volume::GridPtr signedDistanceField(
    const Lattice& lat, const std::vector<std::int32_t>& labels, std::int32_t id, double bandMm)
{
    Mask inside(labels.size()), outside(labels.size());
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, labels.size(), 1 << 16), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                inside[i] = labels[i] == id ? 1 : 0;
                outside[i] = 1 - inside[i];
            }
        });
    const std::vector<float> toInside = squaredDistance(lat, inside, Span::Volume);
    const std::vector<float> toOutside = squaredDistance(lat, outside, Span::Volume);
    // Half the finest spacing: exact in the bound for cubic voxels; on anisotropic
    // ones a surface crossed between slices may be off by up to half the coarser spacing.
    const double half = 0.5 * lat.spacing.minCoeff();
    const auto band = float(bandMm);
    std::vector<float> sdf(labels.size());
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, labels.size(), 1 << 16), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const double d =
                    inside[i] ? -(std::sqrt(double(toOutside[i])) - half) : std::sqrt(double(toInside[i])) - half;
                // No outside voxel in the box (a structure filling it): deep inside.
                sdf[i] = std::isfinite(d) ? std::clamp(float(d), -band, band) : (inside[i] ? -band : band);
            }
        });
    return floatGridFrom(lat, sdf, band);
}

} // namespace voxhap::segmentation
