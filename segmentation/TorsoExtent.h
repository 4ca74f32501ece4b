// SPDX-License-Identifier: Apache-2.0
/// @file TorsoExtent.h
/// @brief Where the torso rules apply: the body's axial cross-sections,
/// measured across the patient (LPS x) in millimetres.
///
/// The CT rules (CtSegmentation.h: lung bases, aorta beside the spine,
/// kidneys, spinal canal, lean tissue as muscle) and the fat | muscle split of
/// MR (MrSegmentation.h) were made for the trunk. In a head, a neck or a limb
/// they invent structures: the brain becomes "muscle", a bright vessel of the
/// head an "aorta". So segmentation first measures each axial slice of the
/// body mask: the width along LPS x of its largest in-plane component (one leg
/// of two, the trunk without the arms beside it). A slice at least
/// kMinTorsoWidthMm across is torso-wide; the torso rules apply from the first
/// torso-wide slice to the last (narrower slices between, a slim waist, stay
/// in), and everywhere else segmentation labels only what does not depend on
/// the anatomy.
///
/// The threshold, from the 2012 US Army anthropometric survey (ANSUR II,
/// Gordon et al. 2014, NATICK/TR-15/007: 6068 adults, women and men; summary
/// statistics of its public data set [mm]):
/// - head breadth: mean 152, range 131–180;
/// - thigh circumference: mean 622, s.d. 58, range 412–870, i.e. a diameter of
///   198 mm on average, 228 mm at the 95th percentile, 277 mm at the largest;
/// - chest breadth: mean 283, s.d. 21, range 213–363 (5th percentile ≈ 249);
/// - waist breadth: mean 318, s.d. 36, range 211–461 (5th percentile ≈ 258);
/// - hip breadth: mean 348, range 264–473.
/// 240 mm [chosen] lies 60 mm above the widest head, above 95 % of thighs and
/// below 95 % of chests and waists. A CT body mask is measured at the skin like
/// these calipers (the soft tissue is not compressed, which adds a little).
/// Children's trunks and the widest thighs fall on the wrong side: a child's
/// abdomen is labelled without the torso rules (soft_tissue, with a note), a
/// very large thigh with them.
///
/// A cross-section that touches the field of view's edge along an in-plane axis
/// pointing left-right is cut: its width is only a lower bound. It counts as
/// torso-wide if even that bound reaches the threshold, and otherwise as
/// evidence of nothing. When every cross-section is cut and none reaches the
/// threshold (a small-field spine CT, a sagittal stack that covers only part
/// of the body, the block phantoms), the anatomy cannot be told: the torso
/// rules apply as they always did, and a note says that the width was not
/// measurable.
#pragma once

#include "segmentation/lattice/Lattice.h"
#include "volume/Volume.h"
#include "volume/mr/BodyWidth.h"

#include <cstdint>
#include <string>
#include <vector>

namespace voxhap::segmentation {

/// Narrowest axial cross-section of an adult torso [mm, LPS x]: the volume
/// library's, which the T1 normalisation's anatomy test uses too (BodyWidth.h).
using volume::kMinTorsoWidthMm;

/// @brief The body's cross-section widths per slice and the slices where the torso rules apply.
struct TorsoExtent {
    /// Per lattice slice (along Lattice::sliceAxis): LPS x width of the largest
    /// in-plane component of the body, voxel faces included [mm]; 0 without body.
    std::vector<double> widthMm;
    int first = -1; ///< first slice of the torso range; -1 if no slice is torso-wide
    int last = -1;  ///< last slice of the torso range, inclusive
    /// Per lattice slice: 1 if its largest body component is cut by the field of
    /// view left or right (widthMm is then a lower bound).
    std::vector<std::uint8_t> cut;
    int bodySlices = 0;  ///< slices holding body
    int torsoSlices = 0; ///< slices holding body within [first, last]
    /// Every cross-section is cut and none reaches the threshold: the torso range
    /// is the whole body, by default rather than by measurement.
    bool undetermined = false;

    bool inTorso(int slice) const { return first >= 0 && slice >= first && slice <= last; }
    /// @brief The torso rules apply to every slice of the body (and there is body).
    bool all() const { return bodySlices > 0 && torsoSlices == bodySlices; }
    /// @brief The torso rules apply nowhere.
    bool none() const { return torsoSlices == 0; }
    /// @brief The widest cross-section [mm]; 0 without body.
    double widestMm() const;
    /// @brief The widest cross-section outside the torso range [mm]; 0 if none.
    double widestOutsideMm() const;
};

/// @brief Labels from the automatic rules, where the torso rules applied, and
/// what the report must tell the user.
struct AutomaticLabels {
    /// The box the labels cover: the volume's, or a part of it holding every
    /// labelled voxel (air beyond it).
    Lattice lattice;
    std::vector<std::int32_t> labels; ///< tissue id per voxel of lattice
    TorsoExtent extent;
    std::vector<std::string> notes; ///< one line each
};

/// @brief Measure the cross-sections of @p body.
/// @param v gives the world geometry (LPS x of each voxel)
TorsoExtent torsoExtent(const volume::Volume& v, const Lattice& lat, const Mask& body);

/// @brief World z of the centre of lattice slice @p slice [mm, LPS], for messages.
double sliceZ(const volume::Volume& v, const Lattice& lat, int slice);

/// @brief One line for the report where the torso rules did not apply
/// everywhere, naming the widths and what was labelled instead; empty if they did.
/// @param rules    what was not applied, e.g. "CT torso rules"
/// @param instead  what the voxels outside the torso range got instead
std::string torsoNote(const volume::Volume& v, const Lattice& lat, const TorsoExtent& e, const std::string& rules,
    const std::string& instead);

} // namespace voxhap::segmentation
