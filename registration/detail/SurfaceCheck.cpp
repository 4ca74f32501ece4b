// SPDX-License-Identifier: Apache-2.0
/// @file SurfaceCheck.cpp
/// @brief Skin-to-skin distance through ITK's signed Maurer distance map, and
/// the overlap of the two fields of view.

#include "registration/detail/SurfaceCheck.h"

#include <itkImage.h>
#include <itkSignedMaurerDistanceMapImageFilter.h>

#include <algorithm>
#include <cmath>

namespace voxhap::registration::detail {

namespace {

using MaskImage = itk::Image<unsigned char, 3>;
using DistanceImage = itk::Image<float, 3>;

/// Distance to the MR body's surface at every MR voxel [mm] (unsigned).
std::vector<float> surfaceDistanceMap(const LevelImage& mr)
{
    auto mask = MaskImage::New();
    MaskImage::SizeType size;
    MaskImage::SpacingType spacing;
    for (unsigned a = 0; a < 3; ++a) {
        size[a] = itk::SizeValueType(mr.dims[int(a)]);
        spacing[a] = mr.geometry.spacing[int(a)];
    }
    mask->SetRegions(MaskImage::RegionType(size));
    mask->SetSpacing(spacing); // distances in mm; origin and direction do not change them
    mask->Allocate();
    std::copy(mr.body.begin(), mr.body.end(), mask->GetBufferPointer());
    auto filter = itk::SignedMaurerDistanceMapImageFilter<MaskImage, DistanceImage>::New();
    filter->SetInput(mask);
    filter->SetBackgroundValue(0);
    filter->SetUseImageSpacing(true);
    filter->SetSquaredDistance(false);
    filter->SetInsideIsPositive(false);
    filter->Update();
    const DistanceImage* out = filter->GetOutput();
    const float* d = out->GetBufferPointer();
    std::vector<float> result(d, d + mr.count());
    for (float& v : result) v = std::abs(v);
    return result;
}

/// Trilinear reading of a dense map at a continuous index (clamped inside).
double trilinear(const LevelImage& li, const std::vector<float>& map, const Vec3d& ijk)
{
    const Vec3d p = ijk.cwiseMax(Vec3d::Zero()).cwiseMin((li.dims - Vec3i::Ones()).cast<double>());
    const Vec3i base = p.cast<int>().cwiseMin(li.dims - Vec3i::Ones());
    const Vec3d f = p - base.cast<double>();
    double sum = 0.0;
    for (int c = 0; c < 8; ++c) {
        const Vec3i o((c & 1), (c >> 1) & 1, (c >> 2) & 1);
        const Vec3i q = (base + o).cwiseMin(li.dims - Vec3i::Ones());
        double w = 1.0;
        for (int a = 0; a < 3; ++a) w *= o[a] ? f[a] : 1.0 - f[a];
        sum += w * double(map[std::size_t(li.index(q.x(), q.y(), q.z()))]);
    }
    return sum;
}

/// Inside the image by at least @p margin voxels on every side.
bool insideBy(const LevelImage& li, const Vec3d& ijk, double margin)
{
    for (int a = 0; a < 3; ++a) {
        if (!(ijk[a] >= margin && ijk[a] <= double(li.dims[a] - 1) - margin)) return false;
    }
    return true;
}

} // namespace

SurfaceDistance surfaceDistance(const LevelImage& ct, const LevelImage& mr, const AffineMap& mrFromCt)
{
    SurfaceDistance out;
    // An MR whose body fills its field of view has no skin to measure against.
    if (std::find(mr.body.begin(), mr.body.end(), std::uint8_t(0)) == mr.body.end()) return out;
    if (std::find(mr.body.begin(), mr.body.end(), std::uint8_t(1)) == mr.body.end()) return out;
    const std::vector<float> map = surfaceDistanceMap(mr);
    double sum = 0.0;
    auto body = [&](int i, int j, int k) { return ct.body[std::size_t(ct.index(i, j, k))] != 0; };
    for (int k = 1; k + 1 < ct.dims.z(); ++k) {
        for (int j = 1; j + 1 < ct.dims.y(); ++j) {
            for (int i = 1; i + 1 < ct.dims.x(); ++i) {
                // A skin voxel: in the body with a face neighbour in air. Voxels on
                // the image's border are left out: there the field of view cuts the body.
                if (!body(i, j, k)) continue;
                if (body(i - 1, j, k) && body(i + 1, j, k) && body(i, j - 1, k) && body(i, j + 1, k) &&
                    body(i, j, k - 1) && body(i, j, k + 1))
                    continue;
                const Vec3d m = mr.toIndex(mrFromCt.apply(ct.world(Vec3d(i, j, k))));
                // Two MR voxels from its faces: the MR's own cut faces are not skin.
                if (!insideBy(mr, m, 2.0)) continue;
                sum += trilinear(mr, map, m);
                ++out.points;
            }
        }
    }
    out.meanMm = out.points ? sum / double(out.points) : 0.0;
    return out;
}

double overlapFraction(const LevelImage& ct, const LevelImage& mr, const AffineMap& mrFromCt)
{
    const AffineMap ctFromMr = mrFromCt.inverse();
    std::int64_t inside = 0, total = 0;
    for (int k = 0; k < mr.dims.z(); ++k) {
        for (int j = 0; j < mr.dims.y(); ++j) {
            for (int i = 0; i < mr.dims.x(); ++i) {
                if (!mr.body[std::size_t(mr.index(i, j, k))]) continue;
                ++total;
                if (ct.inside(ctFromMr.apply(mr.world(Vec3d(i, j, k))))) ++inside;
            }
        }
    }
    return total ? double(inside) / double(total) : 0.0;
}

} // namespace voxhap::registration::detail
