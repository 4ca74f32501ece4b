// SPDX-License-Identifier: Apache-2.0
/// @file FusionRecord.cpp
/// @brief The record to and from JSON.

#include "volume/FusionRecord.h"

#include "core/Errors.h"

#include <nlohmann/json.hpp>

namespace voxhap::volume {

nlohmann::json toJson(const FusionRecord& r)
{
    nlohmann::json m = nlohmann::json::array();
    for (int row = 0; row < 4; ++row) {
        m.push_back({r.mrFromCt(row, 0), r.mrFromCt(row, 1), r.mrFromCt(row, 2), r.mrFromCt(row, 3)});
    }
    return {{"mr_from_ct", m}, {"itk_transform", r.itkTransform}, {"started_from", r.startedFrom},
        {"metric_geometry", r.metricGeometry}, {"metric_start", r.metricStart}, {"metric_final", r.metricFinal},
        {"iterations", r.iterations}, {"stop_reason", r.stopReason}, {"converged", r.converged},
        {"warnings", r.warnings}, {"overlap_start", r.overlapStart}, {"overlap_final", r.overlapFinal},
        {"surface_distance_mm", r.surfaceDistanceMm}, {"surface_limit_mm", r.surfaceLimitMm}, {"seconds", r.seconds},
        {"channel_sources", r.channelSources}, {"mr_path", r.mrPath}, {"mr_series", r.mrSeries},
        {"mr_volume", r.mrVolume}};
}

FusionRecord fusionRecordFromJson(const nlohmann::json& j, const std::string& where)
{
    FusionRecord r;
    try {
        const auto& m = j.at("mr_from_ct");
        if (!m.is_array() || m.size() != 4) throw ValueError("mr_from_ct: expected four rows");
        for (int row = 0; row < 4; ++row) {
            const auto& line = m.at(std::size_t(row));
            if (!line.is_array() || line.size() != 4) throw ValueError("mr_from_ct: expected four columns");
            for (int col = 0; col < 4; ++col) r.mrFromCt(row, col) = line.at(std::size_t(col)).get<double>();
        }
        r.itkTransform = j.at("itk_transform").get<std::string>();
        r.startedFrom = j.at("started_from").get<std::string>();
        r.metricGeometry = j.at("metric_geometry").get<double>();
        r.metricStart = j.at("metric_start").get<double>();
        r.metricFinal = j.at("metric_final").get<double>();
        r.iterations = j.at("iterations").get<std::int64_t>();
        r.stopReason = j.at("stop_reason").get<std::string>();
        r.converged = j.at("converged").get<bool>();
        r.warnings = j.at("warnings").get<std::vector<std::string>>();
        r.overlapStart = j.at("overlap_start").get<double>();
        r.overlapFinal = j.at("overlap_final").get<double>();
        r.surfaceDistanceMm = j.at("surface_distance_mm").get<double>();
        r.surfaceLimitMm = j.at("surface_limit_mm").get<double>();
        r.seconds = j.at("seconds").get<double>();
        r.channelSources = j.at("channel_sources").get<std::map<std::string, std::string>>();
        r.mrPath = j.value("mr_path", std::string());
        r.mrSeries = j.value("mr_series", std::string());
        r.mrVolume = j.value("mr_volume", std::int64_t(0));
    } catch (const nlohmann::json::exception& e) {
        throw ValueError(where + ": fusion record: " + e.what());
    } catch (const ValueError& e) {
        throw ValueError(where + ": fusion record: " + e.what());
    }
    return r;
}

} // namespace voxhap::volume
