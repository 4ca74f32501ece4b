// SPDX-License-Identifier: Apache-2.0
/// @file FusedLabels.cpp
/// @brief The CT's labels, then the MR's T1 over the CT's soft tissue.

#include "segmentation/FusedLabels.h"

#include "core/Errors.h"
#include "volume/Grids.h"

#include <openvdb/tree/LeafManager.h>
#include <tbb/enumerable_thread_specific.h>

#include <atomic>

namespace voxhap::segmentation {

using volume::Channel;

namespace {

/// Fluid: T1 above this multiple of muscle's keeps the CT's label (MrSegmentation.h's rule).
constexpr double kFluidOverMuscle = 2.0;

} // namespace

double fatMuscleSplitMs(const volume::TissueTable& table, volume::FieldStrength field)
{
    const double fat = table.at("fat").t1(field), muscle = table.at("muscle").t1(field);
    return 2.0 / (1.0 / fat + 1.0 / muscle);
}

FusedLabelReport labelFused(
    volume::Volume& v, const volume::TissueTable& table, volume::FieldStrength field, const SegmentOptions& options)
{
    if (!v.has(Channel::Hu)) throw ValueError("fused labels: the volume has no hu grid (a CT is needed)");
    FusedLabelReport out;
    out.ct = segment(v, table, options); // the hu grid is preferred: CT rules
    if (!v.has(Channel::T1)) {
        out.note = v.has(Channel::Intensity) ? "the MR is " +
                (v.metadata().mrWeighting ? std::string(volume::mrWeightingName(*v.metadata().mrWeighting))
                                          : std::string("of unknown weighting")) +
                ", not T1: the labels come from the CT alone"
                                             : "no MR channel: the labels come from the CT alone";
        return out;
    }
    out.thresholdMs = fatMuscleSplitMs(table, field);
    const double fluidMs = kFluidOverMuscle * table.at("muscle").t1(field);
    const std::int32_t fat = table.at("fat").id, muscle = table.at("muscle").id;
    const std::int32_t soft = table.at("soft_tissue").id;

    const auto t1 = volume::t1Grid(v);
    auto labels = volume::labelGrid(v)->deepCopy();
    labels->tree().voxelizeActiveTiles();
    struct Counts {
        std::int64_t soft = 0, withT1 = 0, changed = 0;
    };
    tbb::enumerable_thread_specific<Counts> counts;
    openvdb::tree::LeafManager<volume::LabelGrid::TreeType> leaves(labels->tree());
    leaves.foreach ([&](volume::LabelGrid::TreeType::LeafNodeType& leaf, std::size_t) {
        auto acc = t1->getConstAccessor();
        Counts& c = counts.local();
        for (auto it = leaf.beginValueOn(); it; ++it) {
            const std::int32_t label = *it;
            if (label != fat && label != muscle && label != soft) continue;
            ++c.soft;
            float value = 0.0f;
            if (!acc.probeValue(it.getCoord(), value)) continue;
            ++c.withT1;
            if (double(value) > fluidMs) continue;
            const std::int32_t mr = double(value) < out.thresholdMs ? fat : muscle;
            if (mr != label) {
                it.setValue(mr);
                ++c.changed;
            }
        }
    });
    for (const Counts& c : counts) {
        out.softTissueVoxels += c.soft;
        out.withT1 += c.withT1;
        out.changed += c.changed;
    }
    labels->tree().prune();
    v.setGrid(Channel::Label, labels);
    return out;
}

} // namespace voxhap::segmentation
