// SPDX-License-Identifier: Apache-2.0
/// @file FusedLabels.h
/// @brief Labels of a fused CT and MR (registration/Fusion.h), from both scans:
/// the CT's labels everywhere, bone always from the CT, and where the MR gives
/// T1 the CT's soft tissue (fat, muscle, soft_tissue) becomes fat or muscle by
/// its T1 (docs/reference.md "CT and MR fusion", physics.md §5.5).
///
/// The split between fat and muscle is the T1 of a voxel holding equal parts
/// of both: relaxation rates add in a voxel (fast exchange), so it is the
/// harmonic mean of the table's fat and muscle T1 at the MR's field strength
/// [chosen]. Fluid (T1 above twice muscle's: CSF, cysts) keeps the CT's label.
#pragma once

#include "segmentation/Segmentation.h"
#include "volume/TissueTable.h"
#include "volume/Volume.h"

#include <cstdint>
#include <string>

namespace voxhap::segmentation {

struct FusedLabelReport {
    SegmentReport ct;                  ///< the CT's labelling (segment() on the hu grid)
    std::int64_t softTissueVoxels = 0; ///< CT voxels labelled fat, muscle or soft_tissue
    std::int64_t withT1 = 0;           ///< of which the MR gives T1 for
    std::int64_t changed = 0;          ///< of which the MR's class differs from the CT's label
    double thresholdMs = 0;            ///< the fat–muscle split [ms]
    std::string note;                  ///< why the MR could not label (no t1 grid), else empty
};

/// @brief The T1 [ms] that splits fat from muscle at @p field (harmonic mean of the table's values).
double fatMuscleSplitMs(const volume::TissueTable& table, volume::FieldStrength field);

/// @brief Label @p v (hu and t1 or intensity on one grid) from both channels,
/// storing the label grid and the CT's distance fields (segment()).
/// @throw ValueError if @p v has no hu grid
FusedLabelReport labelFused(volume::Volume& v, const volume::TissueTable& table, volume::FieldStrength field,
    const SegmentOptions& options = {});

} // namespace voxhap::segmentation
