// SPDX-License-Identifier: Apache-2.0
/// @file DenseField.cpp
/// @brief Dense copy and the textbook march.

#include "bench/DenseField.h"

#include "core/Errors.h"
#include "haptic/materials/FieldGrids.h"

#include <cmath>

namespace voxhap::bench {

DenseField::DenseField(const haptic::MaterialField& field)
{
    const auto beta = haptic::detail::dampingGrid(field);
    if (!beta) throw ValueError("dense baseline: no damping grid");
    openvdb::CoordBBox bb = beta->evalActiveVoxelBoundingBox();
    bb.expand(1); // one voxel of background around, as the trilinear reach needs
    mOrigin = volume::fromCoord(bb.min());
    mDims = volume::fromCoord(bb.dim());
    mValues.assign(std::size_t(mDims.x()) * std::size_t(mDims.y()) * std::size_t(mDims.z()), 0.0f);
    // x fastest, as VTK's image data stores it. Filled from the active values
    // (voxels and tiles) directly: plain and obviously right for a baseline.
    const std::size_t nx = std::size_t(mDims.x()), ny = std::size_t(mDims.y());
    for (auto it = beta->cbeginValueOn(); it; ++it) {
        openvdb::CoordBBox box;
        it.getBoundingBox(box);
        box.intersect(bb);
        const float v = *it;
        for (int k = box.min().z(); k <= box.max().z(); ++k)
            for (int j = box.min().y(); j <= box.max().y(); ++j)
                for (int i = box.min().x(); i <= box.max().x(); ++i) {
                    mValues[(std::size_t(k - mOrigin.z()) * ny + std::size_t(j - mOrigin.y())) * nx +
                        std::size_t(i - mOrigin.x())] = v;
                }
    }
    const volume::Geometry g = volume::geometryOf(beta->transform());
    mSpacing = g.spacing;
    const Mat3d linear = g.direction * g.spacing.asDiagonal();
    mWorldToIndex = linear.inverse();
    mWorldToIndexOffset = -mWorldToIndex * g.origin;
    mWorldOrigin = g.origin + linear * mOrigin.cast<double>();
}

double DenseField::march(const haptic::Segment& s, double stepMm, bool trilinear) const noexcept
{
    const double length = (s.tip - s.entry).norm();
    if (!(length > 0.0) || !std::isfinite(length)) return 0.0;
    const Vec3d a = mWorldToIndex * s.entry + mWorldToIndexOffset;
    const Vec3d d = mWorldToIndex * (s.tip - s.entry);
    const long n = std::max(1L, long(std::ceil(length / stepMm)));
    double sum = 0.0;
    for (long i = 0; i <= n; ++i) {
        const Vec3d p = a + d * (double(i) / double(n));
        double v;
        if (trilinear) {
            const int x = int(std::floor(p.x())), y = int(std::floor(p.y())), z = int(std::floor(p.z()));
            const double u = p.x() - x, w = p.y() - y, t = p.z() - z;
            const double c00 = at(x, y, z) * (1 - u) + at(x + 1, y, z) * u;
            const double c10 = at(x, y + 1, z) * (1 - u) + at(x + 1, y + 1, z) * u;
            const double c01 = at(x, y, z + 1) * (1 - u) + at(x + 1, y, z + 1) * u;
            const double c11 = at(x, y + 1, z + 1) * (1 - u) + at(x + 1, y + 1, z + 1) * u;
            v = (c00 * (1 - w) + c10 * w) * (1 - t) + (c01 * (1 - w) + c11 * w) * t;
        } else {
            v = at(int(std::lround(p.x())), int(std::lround(p.y())), int(std::lround(p.z())));
        }
        sum += (i == 0 || i == n) ? 0.5 * v : v;
    }
    return sum * length / double(n);
}

} // namespace voxhap::bench
