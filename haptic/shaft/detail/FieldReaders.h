// SPDX-License-Identifier: Apache-2.0
/// @file FieldReaders.h
/// @brief What every shaft integrator holds: the field's grids, a reader per
/// grid (its own accessors, so one per thread) and the active box.
#pragma once

#include "core/Errors.h"
#include "haptic/materials/FieldGrids.h"
#include "haptic/shaft/detail/LeafReader.h"
#include "haptic/shaft/detail/Traversal.h"
#include "haptic/shaft/detail/VoxelWalk.h"

#include <optional>
#include <string>

namespace voxhap::haptic::detail {

using FloatReader = LeafReader<FloatGrid::TreeType>;
using LabelReader = LeafReader<LabelGrid::TreeType>;
using FloatCursor = WalkCursor<FloatGrid::TreeType>;
using LabelCursor = WalkCursor<LabelGrid::TreeType>;

struct FieldReaders {
    /// @param who names the strategy in errors
    /// @throw ValueError if @p needDamping and the field has no damping grid, or it has no grid at all
    FieldReaders(const MaterialField& field, bool trackLabels, bool needDamping, const std::string& who)
        : beta(dampingGrid(field)), labels(trackLabels ? labelGrid(field) : nullptr)
    {
        if (needDamping && !beta) throw ValueError(who + ": the material field has no damping grid");
        if (!beta && !labels) throw ValueError(who + ": the material field has neither damping nor labels");
        xform = beta ? beta->transformPtr() : labels->transformPtr();
        indexMap = AffineIndexMap(*xform);
        if (beta) {
            betaReader.emplace(beta->tree());
            betaCursor.emplace(beta->tree());
        }
        if (labels) {
            labelReader.emplace(labels->tree());
            labelCursor.emplace(labels->tree());
        }
    }
    FieldReaders(const FieldReaders& o) : beta(o.beta), labels(o.labels), xform(o.xform), indexMap(o.indexMap)
    {
        if (o.betaReader) betaReader.emplace(*o.betaReader); // fresh accessors
        if (o.labelReader) labelReader.emplace(*o.labelReader);
        if (o.betaCursor) betaCursor.emplace(*o.betaCursor);
        if (o.labelCursor) labelCursor.emplace(*o.labelCursor);
    }
    FieldReaders& operator=(const FieldReaders&) = delete;

    /// @brief The union of the grids' active boxes as voxel cells in the shifted
    /// (+0.5) frame, grown by @p pad; empty grids give lo > hi.
    void box(double pad, openvdb::Vec3d& lo, openvdb::Vec3d& hi) const
    {
        lo = openvdb::Vec3d(std::numeric_limits<double>::max());
        hi = openvdb::Vec3d(std::numeric_limits<double>::lowest());
        for (const openvdb::GridBase* g :
            {static_cast<const openvdb::GridBase*>(beta.get()), static_cast<const openvdb::GridBase*>(labels.get())}) {
            if (!g) continue;
            openvdb::Vec3d l, h;
            activeBox(*g, pad, l, h);
            if (l[0] > h[0]) continue;
            lo = openvdb::math::minComponent(lo, l);
            hi = openvdb::math::maxComponent(hi, h);
        }
        if (lo[0] > hi[0]) {
            lo = openvdb::Vec3d(1.0);
            hi = openvdb::Vec3d(-1.0);
        }
    }

    FloatReader* betaPtr() { return betaReader ? &*betaReader : nullptr; }
    LabelReader* labelPtr() { return labelReader ? &*labelReader : nullptr; }
    FloatCursor* betaCursorPtr() { return betaCursor ? &*betaCursor : nullptr; }
    LabelCursor* labelCursorPtr() { return labelCursor ? &*labelCursor : nullptr; }

    FloatGrid::ConstPtr beta;
    LabelGrid::ConstPtr labels;
    openvdb::math::Transform::ConstPtr xform;
    AffineIndexMap indexMap; ///< xform, for the per-tick conversions
    std::optional<FloatReader> betaReader;
    std::optional<LabelReader> labelReader;
    std::optional<FloatCursor> betaCursor; ///< for the exact chord pass (VoxelWalk.h)
    std::optional<LabelCursor> labelCursor;
};

} // namespace voxhap::haptic::detail
