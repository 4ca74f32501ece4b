// SPDX-License-Identifier: Apache-2.0
/// @file SliceResample.cpp
/// @brief Bilinear-in-plane, linear-across-planes resampling of slice stacks.

#include "volume/dicom/detail/SliceResample.h"

#include <algorithm>
#include <cmath>

namespace voxhap::volume {

SliceResampler::SliceResampler(const SliceStackGeometry& stack, const float* input, int nx, int ny, const Vec3d& row,
    const Vec3d& col, const Eigen::Vector2d& spacing, float outside)
    : mStack(stack), mInput(input), mNx(nx), mNy(ny), mRow(row), mCol(col), mSpacing(spacing), mOutside(outside)
{
    for (const auto& s : stack.slices) mAlong.push_back(s.position.dot(stack.normal));
}

float SliceResampler::bilinear(std::size_t slice, double u, double v) const
{
    // Half a pixel past the outermost centres still belongs to the image.
    if (u < -0.5 || v < -0.5 || u > mNx - 0.5 || v > mNy - 0.5) return mOutside;
    const double uc = std::clamp(u, 0.0, double(mNx - 1)), vc = std::clamp(v, 0.0, double(mNy - 1));
    const int i0 = std::min(int(uc), mNx - 2 < 0 ? 0 : mNx - 2), j0 = std::min(int(vc), mNy - 2 < 0 ? 0 : mNy - 2);
    const int i1 = std::min(i0 + 1, mNx - 1), j1 = std::min(j0 + 1, mNy - 1);
    const double fu = uc - i0, fv = vc - j0;
    const float* img = mInput + std::size_t(mNx) * std::size_t(mNy) * slice;
    const auto at = [&](int i, int j) { return double(img[std::size_t(j) * std::size_t(mNx) + std::size_t(i)]); };
    return float((1 - fv) * ((1 - fu) * at(i0, j0) + fu * at(i1, j0)) + fv * ((1 - fu) * at(i0, j1) + fu * at(i1, j1)));
}

void SliceResampler::sample(const Vec3d& planeOrigin, int outNx, int outNy, float* out) const
{
    const double a = planeOrigin.dot(mStack.normal);
    const auto hi = std::lower_bound(mAlong.begin(), mAlong.end(), a);
    std::size_t s1 = std::size_t(std::min<std::ptrdiff_t>(hi - mAlong.begin(), std::ptrdiff_t(mAlong.size()) - 1));
    std::size_t s0 = s1 > 0 ? s1 - 1 : 0;
    double t = 0; // weight of s1
    if (s1 != s0 && mAlong[s1] > mAlong[s0]) t = std::clamp((a - mAlong[s0]) / (mAlong[s1] - mAlong[s0]), 0.0, 1.0);
    if (t == 1.0) s0 = s1;
    for (int j = 0; j < outNy; ++j) {
        for (int i = 0; i < outNx; ++i) {
            const Vec3d w = planeOrigin + i * mSpacing[0] * mRow + j * mSpacing[1] * mCol;
            const auto pixel = [&](std::size_t s) {
                const Vec3d rel = w - mStack.slices[s].position;
                return bilinear(s, rel.dot(mRow) / mSpacing[0], rel.dot(mCol) / mSpacing[1]);
            };
            const float v0 = pixel(s0);
            out[std::size_t(j) * std::size_t(outNx) + std::size_t(i)] =
                (t == 0.0 || s0 == s1) ? v0 : float((1 - t) * v0 + t * pixel(s1));
        }
    }
}

} // namespace voxhap::volume
