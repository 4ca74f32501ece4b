// SPDX-License-Identifier: Apache-2.0
/// @file Phantom.cpp
/// @brief What every phantom shares: rasterising the model and recording its
/// layer table and landmarks in the volume's metadata.

#include "volume/phantoms/Phantoms.h"

#include "core/Errors.h"

#include <nlohmann/json.hpp>

namespace voxhap::volume {

namespace {

using Json = nlohmann::json;

Json toJson(const Vec3d& v) { return Json::array({v.x(), v.y(), v.z()}); }

Vec3d vecFrom(const Json& j, const std::string& what, const char* key = kLayersKey)
{
    if (!j.is_array() || j.size() != 3 || !j[0].is_number() || !j[1].is_number() || !j[2].is_number()) {
        throw ValueError("metadata 'voxhap." + std::string(key) + "': '" + what + "' is not [x, y, z]");
    }
    return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

} // namespace

Volume makePhantom(const PhantomModel& model, const GridSpec& grid, const TissueTable& table)
{
    Volume v = rasterize(model.classify, model.bounds, grid, table);
    v.metadata().source = "voxhap phantom " + model.kind;
    v.metadata().description = model.description;

    const Vec3d path = model.pathTarget - model.pathEntry;
    const auto layers = traceLayers(model.classify, model.pathEntry, path, path.norm(), table);
    Json jl = Json::array();
    for (const auto& l : layers) {
        jl.push_back({{"tissue", l.name}, {"id", l.tissue}, {"start_mm", l.startMm}, {"end_mm", l.endMm}});
    }
    const Json layerDoc = {
        {"entry", toJson(model.pathEntry)}, {"direction", toJson(path.normalized())}, {"layers", jl}};
    v.metadata().extra[kLayersKey] = layerDoc.dump();

    Json marks = Json::object();
    for (const auto& [name, point] : model.landmarks) marks[name] = toJson(point);
    v.metadata().extra[kLandmarksKey] = marks.dump();
    return v;
}

std::optional<PhantomLayers> phantomLayers(const Volume& v)
{
    const auto it = v.metadata().extra.find(kLayersKey);
    if (it == v.metadata().extra.end()) return std::nullopt;
    Json doc;
    try {
        doc = Json::parse(it->second);
    } catch (const Json::parse_error&) {
        throw ValueError("metadata 'voxhap." + std::string(kLayersKey) + "' is not valid JSON");
    }
    PhantomLayers out;
    if (!doc.is_object() || !doc.contains("layers") || !doc["layers"].is_array()) {
        throw ValueError("metadata 'voxhap." + std::string(kLayersKey) + "' has no 'layers' array");
    }
    out.entry = vecFrom(doc.value("entry", Json()), "entry");
    out.direction = vecFrom(doc.value("direction", Json()), "direction");
    for (const auto& l : doc["layers"]) {
        LayerSpan s;
        try {
            s.name = l.at("tissue").get<std::string>();
            s.tissue = l.at("id").get<int>();
            s.startMm = l.at("start_mm").get<double>();
            s.endMm = l.at("end_mm").get<double>();
        } catch (const Json::exception&) {
            throw ValueError(
                "metadata 'voxhap." + std::string(kLayersKey) + "': a layer lacks tissue, id, start_mm or end_mm");
        }
        out.layers.push_back(std::move(s));
    }
    return out;
}

std::optional<Vec3d> phantomLandmark(const Volume& v, const std::string& name)
{
    const auto it = v.metadata().extra.find(kLandmarksKey);
    if (it == v.metadata().extra.end()) return std::nullopt;
    const Json marks = Json::parse(it->second, nullptr, /*allow_exceptions=*/false);
    if (!marks.is_object())
        throw ValueError("metadata 'voxhap." + std::string(kLandmarksKey) + "' is not a JSON object");
    if (!marks.contains(name)) return std::nullopt;
    return vecFrom(marks[name], name, kLandmarksKey);
}

} // namespace voxhap::volume
