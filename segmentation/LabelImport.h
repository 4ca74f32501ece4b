// SPDX-License-Identifier: Apache-2.0
/// @file LabelImport.h
/// @brief Imported label maps (e.g. a segmentation exported from 3D Slicer as
/// NRRD or NIfTI) and the mapping file from their values to tissue ids.
///
/// Mapping file (JSON):
///
///     {"schema": "voxhap.label-mapping/1",
///      "file": "segmentation.nrrd",
///      "labels": {"1": "kidney", "2": "aorta", "7": 17}}
///
/// "file" (optional) names the label map, relative to the mapping file.
/// Each key is a value of the label map; each value a tissue name or id from
/// the tissue table. A label-map value of 0 means "no label here". A non-zero
/// value the mapping does not list is refused, so that a structure is never
/// dropped silently.
#pragma once

#include "segmentation/lattice/Lattice.h"
#include "volume/TissueTable.h"
#include "volume/Volume.h"

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace voxhap::segmentation {

/// @brief Label-map value → tissue id.
struct LabelMapping {
    std::map<std::int64_t, std::int32_t> tissueOf;
    std::string origin;         ///< the file, for messages
    std::filesystem::path file; ///< the label map the mapping names, resolved; empty if none
    /// (imported tissue, automatic tissue): where the map says the first and the
    /// automatic labels say the second, the automatic label stays (TotalSegmentator's
    /// bones keep the cortex the CT numbers found). A mapped tissue of −1 keeps the
    /// automatic label everywhere.
    std::vector<std::pair<std::int32_t, std::int32_t>> keepAutomatic;
};

/// @brief Read and check a mapping file against @p table. @throw IoError, ValueError
/// naming the file and the field
LabelMapping loadLabelMapping(const std::filesystem::path& file, const volume::TissueTable& table);
/// @brief Parse mapping JSON text; @p origin names it in messages.
LabelMapping parseLabelMapping(const std::string& json, const std::string& origin, const volume::TissueTable& table);

/// @brief The tissue ids the label map @p labels (any geometry) gives the voxels
/// of @p lat in @p target, by nearest neighbour in world space; −1 where it has
/// no label (value 0, or outside its extent).
/// @param file names the label map in messages
/// @throw ValueError naming @p file if a value is not an integer or not in the mapping
std::vector<std::int32_t> resampleLabels(const volume::Volume& labels, const LabelMapping& mapping,
    const volume::Volume& target, const Lattice& lat, const std::string& file);

/// @brief Overwrite @p ids with the imported ids where they are set (≥ 0).
/// @return how many voxels changed label
std::int64_t applyImported(std::vector<std::int32_t>& ids, const std::vector<std::int32_t>& imported);

} // namespace voxhap::segmentation
