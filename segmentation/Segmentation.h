// SPDX-License-Identifier: Apache-2.0
/// @file Segmentation.h
/// @brief One call from a loaded volume to its label grid, imported labels
/// and critical-structure distance fields, with a per-label summary.
#pragma once

#include "core/Progress.h"
#include "segmentation/LabelImport.h"
#include "volume/TissueTable.h"
#include "volume/Volume.h"

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::segmentation {

/// @brief An imported label map and its mapping (LabelImport.h).
struct ImportedLabels {
    const volume::Volume* labels = nullptr;
    LabelMapping mapping;
    std::string file; ///< for messages
};

/// @brief What to compute.
struct SegmentOptions {
    /// Labels from hu (CT), else t1 or intensity (MR). Off: keep the volume's
    /// label grid (or none) and apply only the imported map.
    bool automatic = true;
    std::optional<ImportedLabels> imported; ///< takes precedence over automatic labels
    /// Tissues that get a distance field; empty: those the table marks critical.
    std::vector<std::string> critical;
    /// Distance fields are stored within this distance of the structure [mm]:
    /// clearance beyond it reads as the band [chosen: past the 5–20 mm margins a planner asks for].
    double distanceBandMm = 30.0;
    Progress progress; ///< called as each step starts (fraction -1: not known), with its name; may be empty
    /// Refuse (ValueError, one line naming both) when the volume's grids plus the
    /// estimated working memory (workingBytes) exceed this [bytes]; 0: no cap.
    std::uint64_t memoryCapBytes = 0;
};

/// @brief One label's figures.
struct LabelSummary {
    int id = 0;
    std::string name;
    std::int64_t voxels = 0;
    double ml = 0;
    std::array<Vec3d, 2> bounds{}; ///< world box of the voxel centres [mm, LPS]
};

/// @brief What segment() did.
struct SegmentReport {
    std::string method;                      ///< "ct", "mr", "imported" or "existing"
    std::vector<LabelSummary> labels;        ///< by id, air excluded
    std::vector<std::string> distanceFields; ///< derived-grid names written
    std::int64_t importedVoxels = 0;         ///< voxels whose label the imported map set
    /// What the user must know about how the labels were made, one line each:
    /// rules that did not apply (a head, a limb: TorsoExtent.h), an MR contrast
    /// that cannot tell tissues apart. Empty when the rules applied as made.
    std::vector<std::string> notes;
    /// Automatic labels only (else 0): the width of the body's widest axial
    /// cross-section along LPS x [mm], and the share of the body's slices the
    /// torso rules labelled (1: all, 0: none; TorsoExtent.h). A body cut by the
    /// field of view in every slice is labelled by them throughout (1), and a
    /// note says the anatomy could not be checked.
    double bodyWidthMm = 0;
    double torsoFraction = 0;
    double seconds = 0;
    std::uint64_t inputBytes = 0;   ///< the volume's grids before segmentation (OpenVDB memUsage)
    std::uint64_t workingBytes = 0; ///< the estimate checked against the cap (workingBytes)
};

/// @brief segment()'s estimate of the memory it needs beside the volume's own
/// grids [bytes], before it allocates: its largest set of working arrays at any
/// step (the CT rules on the box that the body can occupy, from the HU grid's
/// active box) and the label grid it adds, plus a fixed 32 MiB for threads and buffers. The distance fields' boxes are
/// known only once the labels are: segment() checks them again then, and the report's figure is the larger of the two.
std::uint64_t workingBytes(const volume::Volume& v, const SegmentOptions& options = {});

/// @brief Label @p v from its hu (preferred), t1 or intensity grid, apply the
/// imported map, store the label grid, and add "sdf.<tissue>" derived grids for
/// the critical tissues present.
/// @throw ValueError if there is nothing to segment from, or a critical name is unknown
SegmentReport segment(volume::Volume& v, const volume::TissueTable& table, const SegmentOptions& options = {});

/// @brief Voxel counts, volumes and boxes of every label in @p v's label grid.
std::vector<LabelSummary> summarizeLabels(const volume::Volume& v, const volume::TissueTable& table);

} // namespace voxhap::segmentation
