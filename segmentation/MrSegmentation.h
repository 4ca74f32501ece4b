// SPDX-License-Identifier: Apache-2.0
/// @file MrSegmentation.h
/// @brief Fat and muscle from MR T1 inside the body mask (Otsu 1979, two classes).
///
/// T1 separates fat (290 ms at 1.5 T) from muscle (856 ms) by a factor of three
/// (physics.md §5.1), so a two-class Otsu split of the body's values finds
/// them without knowing the scanner. Long-T1 fluid (CSF, 4280 ms) is neither:
/// voxels above twice the muscle class's median are labelled soft_tissue.
/// What T1 cannot tell apart — bone (no signal), ligaments, organs — is left
/// to imported label maps (LabelImport.h). For T1-weighted intensities that
/// were not normalised (metadata t1Units other than "ms") the order flips:
/// fat is the bright class and fluid the dark one.
#pragma once

#include "segmentation/Lattice.h"
#include "volume/TissueTable.h"

#include <cstdint>
#include <string>
#include <vector>

namespace voxhap::segmentation {

/// @brief The Otsu threshold of @p values: the split maximising the
/// between-class variance of a 256-bin histogram over [min, max].
double otsuThreshold(const std::vector<float>& values);

/// @brief Tissue ids from dense T1 values (0 = no signal, outside).
/// @param t1InMs true for T1 maps or normalised T1-weighted data (short T1 is fat)
std::vector<std::int32_t> segmentMr(const Lattice& lat, const std::vector<float>& t1, bool t1InMs,
                                    const volume::TissueTable& table);

} // namespace voxhap::segmentation
