// SPDX-License-Identifier: Apache-2.0
/// @file DenseField.h
/// @brief The textbook baseline: a plain dense float array with an affine
/// world->index map, marched at a fixed step (what one writes without OpenVDB).
#pragma once

#include "haptic/shaft/ShaftIntegration.h"

#include <vector>

namespace voxhap::bench {

/// @brief A dense copy of a MaterialField's damping grid over its active box.
class DenseField {
public:
    explicit DenseField(const haptic::MaterialField& field);

    /// @brief ∫β ds by the trapezoid rule with N = ceil(L/step) steps, nearest or trilinear samples [N·s/mm].
    double march(const haptic::Segment& s, double stepMm, bool trilinear) const noexcept;

    const std::vector<float>& values() const { return mValues; }
    const Vec3i& dims() const { return mDims; }
    const Vec3i& origin() const { return mOrigin; } ///< index of values()[0]
    const Vec3d& spacing() const { return mSpacing; }
    const Vec3d& worldOrigin() const { return mWorldOrigin; } ///< world position of values()[0] [mm]

private:
    float at(int i, int j, int k) const noexcept
    {
        i -= mOrigin.x(), j -= mOrigin.y(), k -= mOrigin.z();
        if (i < 0 || j < 0 || k < 0 || i >= mDims.x() || j >= mDims.y() || k >= mDims.z()) return 0.0f;
        return mValues[(std::size_t(k) * std::size_t(mDims.y()) + std::size_t(j)) * std::size_t(mDims.x()) +
            std::size_t(i)];
    }

    std::vector<float> mValues; // x fastest (VTK's layout, so that the probe baseline shares it)
    Vec3i mDims{0, 0, 0}, mOrigin{0, 0, 0};
    Vec3d mSpacing{1, 1, 1}, mWorldOrigin{0, 0, 0};
    Mat3d mWorldToIndex = Mat3d::Identity();
    Vec3d mWorldToIndexOffset{0, 0, 0};
};

} // namespace voxhap::bench
