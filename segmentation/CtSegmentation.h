// SPDX-License-Identifier: Apache-2.0
/// @file CtSegmentation.h
/// @brief Tissue labels from CT numbers: thresholds (physics.md §5.2) plus
/// connectivity, size and shape rules, with morphology in millimetres.
///
/// The steps, each a rule whose constants are named in CtSegmentation.cpp:
/// 1. body: HU ≥ −500, opened in-plane by 5 mm to cut the table and rails
///    off, the largest 3-D component, holes filled per slice;
/// 2. lung: gas (HU < −400) inside the body in components of ≥ 50 ml that
///    are parenchyma rather than bowel gas (few voxels below −950 HU);
/// 3. enhanced structures: HU ≥ 120 after 1 mm smoothing, eroded by 2.5 mm to
///    split touching organs, components grown back, then classified:
///    bone (≥ 5 % of voxels ≥ 600 HU; cortical from 700 HU, the table's
///    cortical minimum, else cancellous), aorta (a tube ≥ 60 mm long with a
///    1.5–12 cm² cross-section, within 60 mm of the spine front to back), kidney
///    (40–400 ml, median 180–300 HU, 30–130 mm lateral of the spine, within 70 mm
///    of it front to back), anything else soft_tissue;
/// 4. fat (−400 ≤ HU < −30, the table's fat maximum), muscle above;
/// 5. skin: the body's outer shell of the table's skin thickness, in-plane;
/// 6. spinal canal: holes of the bone ring closed by 7 mm, per slice, joined
///    across disc levels, at least 30 mm long: labelled spinal_cord.
///
/// Steps 2 to 6 were made for the trunk. Outside its slices (TorsoExtent.h: a
/// head, a neck, a limb), only what CT numbers say whatever the anatomy is
/// kept: the body, its skin shell, bone (regions with dense voxels, cortical
/// from 700 HU), fat (−400 to −30 HU), gas (air) and aerated lung parenchyma
/// (a texture rule, not a place). What the trunk's rules would call muscle,
/// kidney, aorta or spinal canal is soft_tissue there, and a note says so.
#pragma once

#include "segmentation/TorsoExtent.h"
#include "segmentation/lattice/Lattice.h"
#include "volume/Grids.h"
#include "volume/TissueTable.h"
#include "volume/Volume.h"

#include <cstdint>
#include <vector>

namespace voxhap::segmentation {

/// @brief Tissue ids from the HU grid @p hu over @p lat, the torso range, and a
/// note where the torso rules did not apply everywhere. The labels cover the
/// body's box widened by the canal closing (AutomaticLabels::lattice); every
/// voxel beyond it is air. Working memory: about 1.6 bytes per voxel of @p lat
/// for the body mask, then about 14 per voxel of the body's box (ctWorkingBytes).
/// @param v gives the world geometry (left-right for the kidney rule, widths)
/// @throw ValueError if the table lacks a tissue the rules label
AutomaticLabels segmentCt(
    const volume::Volume& v, const Lattice& lat, const volume::FloatGrid& hu, const volume::TissueTable& table);

/// @brief The body mask of step 1 alone (HU ≥ −500, table and rails removed).
Mask ctBodyMask(const Lattice& lat, const std::vector<float>& smoothedHu);

/// @brief The body in a foreground mask (any modality): opened in-plane by 5 mm
/// to cut off the table and rails, the largest 3-D component, grown back,
/// slice islands under 4 cm² dropped, holes filled per slice.
Mask bodyMask(const Lattice& lat, const Mask& foreground);

/// @brief Keep, per slice, the in-plane components of @p m whose area is within [minMm2, maxMm2].
Mask filterSliceIslands(const Lattice& lat, const Mask& m, double minMm2, double maxMm2);

/// @brief Mark as @p skinId every body voxel whose centre lies less than
/// @p thicknessMm under the body surface, measured in-plane.
void markSkin(
    const Lattice& lat, const Mask& body, double thicknessMm, std::int32_t skinId, std::vector<std::int32_t>& labels);

} // namespace voxhap::segmentation
