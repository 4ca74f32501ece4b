// SPDX-License-Identifier: Apache-2.0
/// @file BodyWidth.h
/// @brief How wide a body is across the patient (LPS x): a trunk, or a head
/// or a limb, for the rules that were made for the trunk.
///
/// The per-scan T1 normalisation pins a trunk's fat and muscle (physics.md
/// §5.1) and the CT and MR segmentation rules look for a trunk's organs; in a
/// head the brightest class is white matter, not fat, and there is no muscle
/// to pin. Both ask first whether the body is a trunk.
#pragma once

#include "volume/Volume.h"

namespace voxhap::volume {

/// @brief Narrowest axial cross-section of an adult trunk [mm, LPS x]
/// [chosen]: 240 mm, from the 2012 US Army anthropometric survey (ANSUR II,
/// Gordon et al. 2014, NATICK/TR-15/007; 6068 adults): head breadth 131–180
/// (mean 152), thigh diameter 198 on average and 228 at the 95th percentile,
/// chest breadth 5th percentile ≈ 249, waist breadth 5th percentile ≈ 258.
/// 240 lies 60 mm above the widest head, above 95 % of thighs and below 95 %
/// of chests and waists. A child's trunk falls below it.
inline constexpr double kMinTorsoWidthMm = 240.0;

/// @brief The body's widest axial cross-section along LPS x.
struct BodyWidth {
    double widestMm = 0;    ///< over the cross-sections the field of view does not cut [mm]
    double widestCutMm = 0; ///< over the cut ones: a lower bound of their width [mm]
    int sections = 0;       ///< 2 mm axial sections (LPS z) that hold body
    int cutSections = 0;    ///< of which touch the volume's edge left or right
    /// @brief At least one section was measured whole, or a cut one already reaches a trunk's width.
    bool measured() const { return sections > cutSections || widestCutMm >= kMinTorsoWidthMm; }
    /// @brief The body is a trunk somewhere (measured whole or not).
    bool trunk() const { return std::max(widestMm, widestCutMm) >= kMinTorsoWidthMm; }
};

/// @brief Measure the active voxels of @p body (a grid of @p v) in 2 mm axial
/// sections of world space: each section's LPS x extent, voxel faces included.
/// A section whose voxels touch a face of @p v's extent along an index axis
/// that points more left-right than not is cut by the field of view: its
/// width is only a lower bound.
BodyWidth measureBodyWidth(const Volume& v, const openvdb::GridBase& body);

} // namespace voxhap::volume
