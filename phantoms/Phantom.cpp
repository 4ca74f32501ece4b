// SPDX-License-Identifier: Apache-2.0
/// @file Phantom.cpp
/// @brief What every phantom shares: rasterising the model and recording its
/// layer table and landmarks in the volume's metadata.

#include "phantoms/Phantoms.h"

namespace voxhap::volume {

Volume makePhantom(const PhantomModel& model, const GridSpec& grid, const TissueTable& table)
{
    Volume v = rasterize(model.classify, model.bounds, grid, table);
    VolumeMetadata& md = v.metadata();
    md.source = "voxhap phantom " + model.kind;
    md.description = model.description;

    const Vec3d path = model.pathTarget - model.pathEntry;
    md.phantomLayers = PhantomLayers{
        model.pathEntry, path.normalized(), traceLayers(model.classify, model.pathEntry, path, path.norm(), table)};
    md.landmarks = {model.landmarks.begin(), model.landmarks.end()};
    return v;
}

std::optional<PhantomLayers> phantomLayers(const Volume& v) { return v.metadata().phantomLayers; }

std::optional<Vec3d> phantomLandmark(const Volume& v, const std::string& name)
{
    const auto& marks = v.metadata().landmarks;
    const auto it = marks.find(name);
    if (it == marks.end()) return std::nullopt;
    return it->second;
}

} // namespace voxhap::volume
