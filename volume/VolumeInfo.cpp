// SPDX-License-Identifier: Apache-2.0
/// @file VolumeInfo.cpp
/// @brief Statistics over active voxels (tiles weighted by their voxel count).

#include "volume/VolumeInfo.h"

#include "volume/Grids.h"

#include <cmath>
#include <map>

namespace voxhap::volume {

namespace {

/// Min, max and mean over active values, tiles counted with their voxel count.
template <typename GridT> ChannelSummary summarise(const GridT& grid, const std::string& name, const std::string& type)
{
    ChannelSummary s;
    s.name = name;
    s.valueType = type;
    s.memoryBytes = grid.memUsage();
    double sum = 0.0;
    bool first = true;
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        const auto n = static_cast<std::int64_t>(it.getVoxelCount());
        const double value = double(*it);
        s.activeVoxels += n;
        sum += value * double(n);
        if (first || value < s.min) s.min = value;
        if (first || value > s.max) s.max = value;
        first = false;
    }
    if (s.activeVoxels > 0) s.mean = sum / double(s.activeVoxels);
    return s;
}

} // namespace

VolumeInfo describe(const Volume& v, const TissueTable& table)
{
    VolumeInfo info;
    info.geometry = v.geometry();
    info.box = v.indexBox();
    info.worldBounds = v.worldBounds();
    const Mat3d linear = info.geometry.direction * info.geometry.spacing.asDiagonal();
    info.voxelVolumeMm3 = std::abs(linear.determinant());
    info.denseVoxels = info.box.voxelCount();
    info.metadata = v.metadata();

    if (auto g = huGrid(v)) info.channels.push_back(summarise(*g, "hu", "float"));
    if (auto g = t1Grid(v)) info.channels.push_back(summarise(*g, "t1", "float"));
    if (auto g = intensityGrid(v)) info.channels.push_back(summarise(*g, "intensity", "float"));
    if (auto g = labelGrid(v)) {
        info.channels.push_back(summarise(*g, "label", "int32"));
        std::map<int, std::int64_t> counts;
        for (auto it = g->cbeginValueOn(); it; ++it) counts[*it] += static_cast<std::int64_t>(it.getVoxelCount());
        for (const auto& [id, n] : counts) {
            const Tissue* t = table.find(id);
            info.labels.push_back({id, t ? t->name : "unknown", n, double(n) * info.voxelVolumeMm3 / 1000.0});
        }
    }
    for (const auto& c : info.channels) {
        info.activeVoxels = std::max(info.activeVoxels, c.activeVoxels);
        info.memoryBytes += c.memoryBytes;
    }
    // The typed metadata (VolumeMetadata::phantomLayers) holds the table; phantoms/ writes it.
    if (const auto& layers = v.metadata().phantomLayers) info.layers = layers->layers;
    return info;
}

} // namespace voxhap::volume
