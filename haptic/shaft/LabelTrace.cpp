// SPDX-License-Identifier: Apache-2.0
/// @file LabelTrace.cpp
#include "haptic/shaft/LabelTrace.h"

#include "core/Errors.h"
#include "haptic/shaft/detail/FieldReaders.h"
#include "haptic/shaft/detail/Traversal.h"

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

namespace {

/// Appends the label runs and β pieces of one segment, @p offset mm along the traced path.
struct RunCollector {
    detail::LabelReader& labels;
    detail::FloatReader* beta;
    std::vector<LabelRun>& runs;
    std::vector<DampingPiece>* damping;

    void add(int label, double a, double b, double x)
    {
        if (!runs.empty() && runs.back().label == label)
            runs.back().endMm = b;
        else if (!runs.empty() || label != 0)
            runs.push_back({label, a, b});
        if (!beta || x == 0.0) return;
        if (!damping->empty() && damping->back().beta == x && damping->back().endMm >= a - 1e-9)
            damping->back().endMm = b;
        else
            damping->push_back({a, b, x});
    }
    void walk(const detail::IndexSegment& s, double t0, double t1, double offset)
    {
        const auto cell = [&](const openvdb::Coord& c, double ta, double tb) {
            add(labels.get(c), offset + ta * s.lengthMm, offset + tb * s.lengthMm, beta ? double(beta->get(c)) : 0.0);
        };
        // A block is skipped whole only where labels and β are both uniform over it.
        const auto uniform = [&](const openvdb::Coord& c) {
            const int dim = labels.uniformBlock(c);
            return dim <= 1 || !beta ? dim : std::min(dim, beta->uniformBlock(c));
        };
        detail::walkCellsSkipping(s, t0, t1, 0, uniform, cell, cell);
    }
};

} // namespace

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
    if (damping) damping->clear();
    RunCollector collect{*r.labelPtr(), damping ? r.betaPtr() : nullptr, runs, damping};
    collect.walk(s, t0, t1, 0.0);
    while (!runs.empty() && runs.back().label == 0) runs.pop_back();
    return runs;
}

std::vector<LabelRun> LabelTracer::tracePolyline(
    std::span<const Vec3d> points, std::vector<DampingPiece>* damping) const
{
    namespace d = detail;
    if (!d::polylineValid(points)) throw ValueError("layer trace: the bent path needs two or more finite points");
    auto& mine = mImpl->readers.local();
    if (!mine) mine.emplace(mImpl->prototype);
    d::FieldReaders& r = *mine;
    std::vector<LabelRun> runs;
    if (damping) damping->clear();
    RunCollector collect{*r.labelPtr(), damping ? r.betaPtr() : nullptr, runs, damping};
    double offset = 0.0;
    for (std::size_t i = 1; i < points.size(); ++i) {
        const d::IndexSegment s = d::toIndex(*r.xform, Segment{points[i - 1], points[i]}, 0.5);
        if (!s.valid) continue;
        double t0 = 0.0, t1 = 0.0;
        const double end = offset + s.lengthMm;
        if (!d::clip(s, mImpl->lo, mImpl->hi, t0, t1)) {
            collect.add(0, offset, end, 0.0); // outside the field: air (dropped while it leads)
        } else {
            if (t0 > 0.0) collect.add(0, offset, offset + t0 * s.lengthMm, 0.0);
            collect.walk(s, t0, t1, offset);
            if (t1 < 1.0) collect.add(0, offset + t1 * s.lengthMm, end, 0.0);
        }
        offset = end;
    }
    while (!runs.empty() && runs.back().label == 0) runs.pop_back();
    return runs;
}

std::vector<LabelRun> traceLabelRuns(
    const MaterialField& field, const Vec3d& origin, const Vec3d& direction, double lengthMm)
{
    return LabelTracer(field).trace(origin, direction, lengthMm);
}

} // namespace voxhap::haptic
