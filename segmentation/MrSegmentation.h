// SPDX-License-Identifier: Apache-2.0
/// @file MrSegmentation.h
/// @brief Fat and muscle from MR T1 inside the body mask (Otsu 1979, two classes);
/// the body alone from MR of other contrasts.
///
/// T1 separates fat (290 ms at 1.5 T) from muscle (856 ms) by a factor of three
/// (physics.md §5.1), so a two-class Otsu split of the body's values finds
/// them without knowing the scanner. Long-T1 fluid (CSF, 4280 ms) is neither:
/// voxels above twice the muscle class's median are labelled soft_tissue.
/// What T1 cannot tell apart — bone (no signal), ligaments, organs — is left
/// to imported label maps (LabelImport.h). For T1-weighted intensities that
/// were not normalised (an intensity grid marked T1-weighted) the order flips:
/// fat is the bright class and fluid the dark one.
///
/// Outside the torso (TorsoExtent.h: a head, a neck, a limb) there is no
/// muscle class: a head's white matter is as bright as fat on T1-weighted
/// images (the shared MPRAGE's normalisation puts it at fat's T1), so fat is
/// looked for only in the subcutaneous layer, within 10 mm of the skin (the
/// scalp), by the same split of that layer's values; everything else in the
/// body is soft_tissue, and a note says so.
///
/// An intensity grid of any other weighting (PD, T2, FLAIR, diffusion, field
/// maps, unknown) says nothing about fat against muscle: the body is labelled
/// soft_tissue, without a skin shell or any other class, and a note says why.
#pragma once

#include "segmentation/TorsoExtent.h"
#include "segmentation/lattice/Lattice.h"
#include "volume/TissueTable.h"
#include "volume/Volume.h"

#include <cstdint>
#include <string>
#include <vector>

namespace voxhap::segmentation {

/// @brief The Otsu threshold of @p values: the split maximising the
/// between-class variance of a 256-bin histogram over [min, max].
double otsuThreshold(const std::vector<float>& values);

/// @brief What an MR grid's values say about fat.
enum class MrContrast {
    T1Ms,       ///< T1 [ms] (the t1 grid): fat has the short T1
    T1Weighted, ///< T1-weighted intensities not normalised: fat is bright
    Unknown,    ///< any other weighting (PD, T2, FLAIR, diffusion, unknown): nothing
};

/// @brief Tissue ids from dense MR values (0 = no signal, outside).
/// @param v        world geometry (TorsoExtent.h) and metadata (mrWeighting, for the notes)
/// @param values   the t1 or intensity grid's values over @p lat
/// @param contrast what the values say about fat
AutomaticLabels segmentMr(const volume::Volume& v, const Lattice& lat, const std::vector<float>& values,
    MrContrast contrast, const volume::TissueTable& table);

} // namespace voxhap::segmentation
