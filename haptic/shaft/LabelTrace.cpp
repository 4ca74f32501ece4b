// SPDX-License-Identifier: Apache-2.0
/// @file LabelTrace.cpp
#include "haptic/shaft/LabelTrace.h"

#include "haptic/shaft/detail/FieldReaders.h"
#include "haptic/shaft/detail/Traversal.h"
#include "core/Errors.h"

#include <tbb/enumerable_thread_specific.h>

#include <cmath>
#include <optional>

namespace voxhap::haptic {

struct LabelTracer::Impl {
    detail::FieldReaders prototype;
    openvdb::Vec3d lo, hi;
    mutable tbb::enumerable_thread_specific<std::optional<detail::FieldReaders>> readers;

    explicit Impl(const MaterialField& field)
        : prototype(field, /*trackLabels=*/true, /*needDamping=*/false, "layer trace")
    {
        if (!prototype.labels) throw ValueError("layer trace: the material field has no label grid");
        prototype.box(1.0, lo, hi); // once per tracer: the field's active box, padded one voxel
    }
};

LabelTracer::LabelTracer(const MaterialField& field) : mImpl(std::make_unique<Impl>(field)) { }
LabelTracer::~LabelTracer() = default;

std::vector<LabelRun> LabelTracer::trace(
    const Vec3d& origin, const Vec3d& direction, double lengthMm, std::vector<DampingPiece>* damping) const
{
    namespace d = detail;
    const double n = direction.norm();
    if (!origin.allFinite() || !direction.allFinite() || !(n > 0.0) || !(lengthMm > 0.0) || !std::isfinite(lengthMm)) {
        throw ValueError("layer trace: the path is degenerate (zero or non-finite direction or length)");
    }
    auto& mine = mImpl->readers.local();
    if (!mine) mine.emplace(mImpl->prototype); // fresh accessors for this thread
    d::FieldReaders& r = *mine;
    const Vec3d u = direction / n;
    const d::IndexSegment s = d::toIndex(*r.xform, Segment{origin, origin + lengthMm * u}, 0.5);
    double t0 = 0.0, t1 = 0.0;
    std::vector<LabelRun> runs;
    if (!s.valid || !d::clip(s, mImpl->lo, mImpl->hi, t0, t1)) return runs;
    d::LabelReader& labels = *r.labelPtr();
    d::FloatReader* beta = damping ? r.betaPtr() : nullptr;
    if (damping) damping->clear();
    const auto add = [&](const openvdb::Coord& c, double ta, double tb) {
        const int label = labels.get(c);
        const double a = ta * s.lengthMm, b = tb * s.lengthMm;
        if (!runs.empty() && runs.back().label == label)
            runs.back().endMm = b;
        else if (!runs.empty() || label != 0)
            runs.push_back({label, a, b});
        if (!beta) return;
        const double x = beta->get(c);
        if (x == 0.0) return;
        if (!damping->empty() && damping->back().beta == x && damping->back().endMm >= a - 1e-9)
            damping->back().endMm = b;
        else
            damping->push_back({a, b, x});
    };
    // A block is skipped whole only where labels and β are both uniform over it.
    const auto uniform = [&](const openvdb::Coord& c) {
        const int dim = labels.uniformBlock(c);
        return dim <= 1 || !beta ? dim : std::min(dim, beta->uniformBlock(c));
    };
    d::walkCellsSkipping(s, t0, t1, 0, uniform, add, add);
    while (!runs.empty() && runs.back().label == 0) runs.pop_back();
    return runs;
}

std::vector<LabelRun> traceLabelRuns(
    const MaterialField& field, const Vec3d& origin, const Vec3d& direction, double lengthMm)
{
    return LabelTracer(field).trace(origin, direction, lengthMm);
}

} // namespace voxhap::haptic
