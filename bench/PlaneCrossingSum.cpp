// SPDX-License-Identifier: Apache-2.0
/// @file PlaneCrossingSum.cpp
/// @brief The plane-crossing sum in long double (see the header).

#include "bench/PlaneCrossingSum.h"

#include "core/Errors.h"
#include "volume/Grids.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace voxhap::bench {

struct PlaneCrossingSum::Impl {
    volume::FloatGrid::ConstPtr grid;
    openvdb::math::AffineMap affine;
    double largest = 0.0;
};

PlaneCrossingSum::PlaneCrossingSum(const haptic::MaterialField& field) : mImpl(std::make_unique<Impl>())
{
    mImpl->grid = openvdb::gridConstPtrCast<volume::FloatGrid>(field.damping());
    if (!mImpl->grid) throw ValueError("plane-crossing sum: the material field has no damping grid");
    mImpl->affine = *mImpl->grid->transform().baseMap()->getAffineMap();
    double largest = std::isfinite(mImpl->grid->background()) ? std::abs(mImpl->grid->background()) : 0.0;
    for (auto it = mImpl->grid->cbeginValueAll(); it; ++it) {
        if (std::isfinite(*it)) largest = std::max(largest, double(std::abs(*it)));
    }
    mImpl->largest = largest;
}

PlaneCrossingSum::~PlaneCrossingSum() = default;

double PlaneCrossingSum::largestValue() const { return mImpl->largest; }

double PlaneCrossingSum::integrate(const haptic::Segment& s) const
{
    const double length = (s.tip - s.entry).norm();
    if (!(length > 0.0) || !std::isfinite(length)) return 0.0;
    // The walks' index-space segment: cells [c, c+1)³ in the frame shifted by +0.5.
    const openvdb::Vec3d a = mImpl->affine.applyInverseMap(volume::toVdb(s.entry)) + openvdb::Vec3d(0.5);
    openvdb::Vec3d d = mImpl->affine.applyInverseMap(volume::toVdb(s.tip)) + openvdb::Vec3d(0.5) - a;
    const double scale = std::max({std::abs(d[0]), std::abs(d[1]), std::abs(d[2])});
    for (int i = 0; i < 3; ++i) {
        if (std::abs(d[i]) < 1e-13 * scale) d[i] = 0.0; // as the walks do
    }
    std::vector<long double> ts{0.0L, 1.0L};
    for (int i = 0; i < 3; ++i) {
        if (d[i] == 0.0) continue;
        const long double from = a[i], to = from + (long double)d[i];
        const long double lo = std::min(from, to), hi = std::max(from, to);
        for (long double k = std::floor(lo) + 1.0L; k < hi; k += 1.0L) ts.push_back((k - from) / (long double)d[i]);
    }
    std::sort(ts.begin(), ts.end());
    auto acc = mImpl->grid->getConstAccessor();
    long double sum = 0.0L;
    for (std::size_t j = 0; j + 1 < ts.size(); ++j) {
        const long double mid = 0.5L * (ts[j] + ts[j + 1]);
        const openvdb::Coord c(int(std::floor(a[0] + (long double)d[0] * mid)),
            int(std::floor(a[1] + (long double)d[1] * mid)), int(std::floor(a[2] + (long double)d[2] * mid)));
        const float v = acc.getValue(c);
        if (std::isfinite(v)) sum += (long double)v * (ts[j + 1] - ts[j]);
    }
    return double(sum * (long double)length);
}

} // namespace voxhap::bench
