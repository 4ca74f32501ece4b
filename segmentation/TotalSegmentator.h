// SPDX-License-Identifier: Apache-2.0
/// @file TotalSegmentator.h
/// @brief TotalSegmentator's CT output as imported labels:
/// a built-in mapping from the 117 classes of TotalSegmentator v2's `total`
/// task to voxhap's tissues, and the two forms it writes: one multilabel NIfTI
/// (`--ml`: voxel value = class id) or a folder of per-class masks
/// (`<class name>.nii.gz`, value 1 inside).
///
/// Class ids and names: `class_map["total"]` of `totalsegmentator/map_to_binary.py`
/// in github.com/wasserth/TotalSegmentator (commit 0275d3046117a9615a9876e6e4eefd5156843f1c).
/// No real TotalSegmentator output was tested: its models cannot be downloaded
/// where voxhap is developed; the tests use files made from a phantom.
#pragma once

#include "segmentation/LabelImport.h"
#include "volume/TissueTable.h"
#include "volume/Volume.h"

#include <filesystem>
#include <string>
#include <vector>

namespace voxhap::segmentation {

/// @brief One class of the `total` task and the voxhap tissue it becomes.
struct TotalSegmentatorClass {
    int id;
    const char* name;
    /// A tissue name of data/tissues.json; "bone": cancellous_bone, keeping cortical_bone
    /// where the automatic (CT) labels found it; "": keep the automatic label.
    const char* tissue;
};

/// @brief The 117 classes, by id.
const std::vector<TotalSegmentatorClass>& totalSegmentatorClasses();

/// @brief The class of @p name, or null.
const TotalSegmentatorClass* findTotalSegmentatorClass(const std::string& name);

/// @brief Class id → tissue id for @p table (−1: keep the automatic label), with
/// the bone rule in LabelMapping::keepAutomatic. Values 1000 + id are the tissues
/// of the table themselves (a mask named after a tissue, e.g. lesion.nii.gz).
/// @throw ValueError when the table lacks a tissue the mapping names
LabelMapping totalSegmentatorMapping(const volume::TissueTable& table);

/// @brief Offset of the values that stand for the table's own tissues (per-class masks named after a tissue).
inline constexpr std::int64_t kTissueMaskValue = 1000;

/// @brief Load TotalSegmentator's output: a multilabel file (NIfTI, or any format
/// voxhap reads) as it is, or a folder of per-class masks `<name>.nii[.gz]` merged
/// into one label map of class ids. A mask named after a tissue of @p table (e.g.
/// `lesion.nii.gz`, which TotalSegmentator does not make) labels that tissue and
/// wins over the classes; where class masks overlap, the lower class id wins.
/// @throw IoError, ValueError naming the file: a name that is neither a class nor a
/// tissue, masks of different geometry, a folder without masks
volume::Volume loadTotalSegmentator(const std::filesystem::path& path, const volume::TissueTable& table);

} // namespace voxhap::segmentation
