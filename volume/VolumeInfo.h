// SPDX-License-Identifier: Apache-2.0
/// @file VolumeInfo.h
/// @brief A description of a Volume: geometry, sparsity, memory, value
/// summaries and label census, for `voxhap info` and reports.
#pragma once

#include "volume/TissueTable.h"
#include "volume/Volume.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::volume {

/// @brief Summary of one grid over its active voxels.
struct ChannelSummary {
    std::string name;      ///< "hu", "t1", "intensity" or "label"
    std::string valueType; ///< "float" or "int32"
    std::int64_t activeVoxels = 0;
    std::uint64_t memoryBytes = 0;
    double min = 0, max = 0, mean = 0; ///< over active voxels (0 if none)
};

/// @brief Voxel count of one label.
struct LabelCount {
    int id = 0;
    std::string name; ///< from the tissue table, or "unknown"
    std::int64_t voxels = 0;
    double volumeMl = 0; ///< voxels × voxel volume [ml]
};

/// @brief Everything `voxhap info` reports.
struct VolumeInfo {
    Geometry geometry;
    IndexBox box;
    std::array<Vec3d, 2> worldBounds; ///< [mm, LPS], voxel faces included
    double voxelVolumeMm3 = 0;
    std::int64_t denseVoxels = 0;  ///< voxels of the dense extent
    std::int64_t activeVoxels = 0; ///< largest active count over the grids
    std::uint64_t memoryBytes = 0; ///< all grids
    std::vector<ChannelSummary> channels;
    std::vector<LabelCount> labels; ///< ascending id, non-zero counts only
    VolumeMetadata metadata;
    std::optional<std::vector<LayerSpan>> layers; ///< a phantom's reference-path layers (VolumeMetadata.h)
};

/// @brief Describe a volume; label names come from @p table.
VolumeInfo describe(const Volume& v, const TissueTable& table);

} // namespace voxhap::volume
