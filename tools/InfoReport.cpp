// SPDX-License-Identifier: Apache-2.0
/// @file InfoReport.cpp
/// @brief Formatting of `voxhap info`.

#include "tools/InfoReport.h"
#include "core/Format.h"

#include "tools/FusionReport.h"

#include "phantoms/Phantoms.h"

#include <cstdio>
#include <iomanip>
#include <sstream>

namespace voxhap::tools {

namespace {

using Json = nlohmann::json;

Json vec(const Vec3d& v) { return Json::array({v.x(), v.y(), v.z()}); }
Json vec(const Vec3i& v) { return Json::array({v.x(), v.y(), v.z()}); }

std::string mib(std::uint64_t bytes)
{
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f MiB", double(bytes) / (1024.0 * 1024.0));
    return buf;
}

std::string triple(const Vec3d& v, int digits, const char* sep)
{
    return fixed(v.x(), digits) + sep + fixed(v.y(), digits) + sep + fixed(v.z(), digits);
}

/// Bytes a dense array of the same extent would need: 4 bytes per voxel per grid.
std::uint64_t denseBytes(const volume::VolumeInfo& info)
{
    return std::uint64_t(info.denseVoxels) * 4u * info.channels.size();
}

/// "3T (header: 2.89 T)", "1.5T (assumed)", "7 T (header): neither 1.5 T nor 3 T, no T1 law".
std::string fieldStrengthText(const volume::VolumeMetadata& md)
{
    std::ostringstream s;
    const std::string from(volume::factSourceName(md.fieldStrengthSource));
    if (!md.fieldStrength) {
        s << md.fieldStrengthTesla.value_or(0.0) << " T (" << from << "): neither 1.5 T nor 3 T, no T1 law";
        return s.str();
    }
    s << volume::fieldStrengthName(*md.fieldStrength) << " (" << from;
    if (md.fieldStrengthTesla) s << ": " << *md.fieldStrengthTesla << " T";
    s << ")";
    return s.str();
}

} // namespace

Json infoJson(const volume::VolumeInfo& info, const std::string& file)
{
    Json j;
    j["file"] = file;
    j["modality"] = info.metadata.modality;
    j["source"] = info.metadata.source;
    j["description"] = info.metadata.description;
    j["units"] = {
        {"hu", info.metadata.huUnits}, {"t1", info.metadata.t1Units}, {"intensity", info.metadata.intensityUnits}};
    if (info.metadata.mrWeighting) j["mr_weighting"] = volume::mrWeightingName(*info.metadata.mrWeighting);
    j["dimensions"] = vec(info.box.dims());
    j["index_min"] = vec(info.box.min);
    j["index_max"] = vec(info.box.max);
    j["spacing_mm"] = vec(info.geometry.spacing);
    j["origin_mm"] = vec(info.geometry.origin);
    Json dir = Json::array();
    for (int c = 0; c < 3; ++c) dir.push_back(vec(Vec3d(info.geometry.direction.col(c))));
    j["direction_columns"] = dir;
    j["bounds_mm"] = {{"min", vec(info.worldBounds[0])}, {"max", vec(info.worldBounds[1])}};
    j["voxel_volume_mm3"] = info.voxelVolumeMm3;
    j["dense_voxels"] = info.denseVoxels;
    j["active_voxels"] = info.activeVoxels;
    j["active_fraction"] = info.denseVoxels ? double(info.activeVoxels) / double(info.denseVoxels) : 0.0;
    j["memory_bytes"] = info.memoryBytes;
    j["dense_memory_bytes"] = denseBytes(info);
    Json grids = Json::array();
    for (const auto& c : info.channels) {
        grids.push_back({{"name", c.name}, {"type", c.valueType}, {"active_voxels", c.activeVoxels},
            {"memory_bytes", c.memoryBytes}, {"min", c.min}, {"max", c.max}, {"mean", c.mean}});
    }
    j["grids"] = grids;
    Json labels = Json::array();
    for (const auto& l : info.labels) {
        labels.push_back({{"id", l.id}, {"name", l.name}, {"voxels", l.voxels}, {"volume_ml", l.volumeMl}});
    }
    j["labels"] = labels;
    if (info.layers) {
        Json layers = Json::array();
        for (const auto& l : *info.layers) {
            layers.push_back({{"tissue", l.name}, {"id", l.tissue}, {"start_mm", l.startMm}, {"end_mm", l.endMm},
                {"thickness_mm", l.endMm - l.startMm}});
        }
        j["layers"] = layers;
    }
    // The typed facts by their names (the layers are above), then the notes.
    Json facts = Json::object();
    for (const auto& [k, v] : volume::metadataFacts(info.metadata)) {
        if (k != "modality" && k != "mr_weighting" && k != "layers" && k != "fusion") facts[k] = v;
    }
    if (info.metadata.fusion) j["fusion"] = volume::toJson(*info.metadata.fusion);
    for (const auto& [k, v] : info.metadata.extra) facts[k] = v;
    j["metadata"] = facts;
    return j;
}

void printInfo(std::ostream& os, const volume::VolumeInfo& info, const std::string& file)
{
    const auto row = [&os](const char* key) -> std::ostream& { return os << std::left << std::setw(12) << key; };
    const auto& g = info.geometry;
    row("file") << file << '\n';
    row("source") << info.metadata.source << (info.metadata.description.empty() ? "" : " — ")
                  << info.metadata.description << '\n';
    row("modality") << (info.metadata.modality.empty() ? "unknown" : info.metadata.modality) << '\n';
    const auto extra = [&info](const char* key) {
        const auto it = info.metadata.extra.find(key);
        return it == info.metadata.extra.end() ? std::string() : it->second;
    };
    const volume::VolumeMetadata& md = info.metadata;
    if (!md.modalityReason.empty()) row("") << md.modalityReason << '\n';
    if (md.mrWeighting) {
        row("weighting") << volume::mrWeightingName(*md.mrWeighting) << '\n';
        if (const std::string why = extra("mr_weighting_reason"); !why.empty()) row("") << why << '\n';
        if (const std::string refused = extra("t1_norm_refused"); !refused.empty()) {
            row("") << "not normalised to T1: " << refused << '\n';
        } else if (md.t1Kind == volume::T1Kind::NormalisedWeighted && md.fieldStrength) {
            row("") << "normalised per scan to T1 [ms] at " << volume::fieldStrengthName(*md.fieldStrength) << " (fat "
                    << extra("t1_norm_fat") << ", muscle " << extra("t1_norm_muscle") << ")\n";
        }
        if (const std::string bg = extra("mr_background"); !bg.empty()) row("background") << bg << '\n';
    }
    if (md.fieldStrength || md.fieldStrengthTesla) row("field") << fieldStrengthText(md) << '\n';
    if (md.volumeChoice) row("volume") << volume::volumeChoiceText(*md.volumeChoice) << '\n';
    if (const std::string r = extra("resampled"); !r.empty()) {
        row("resampled") << r << '\n';
        row("") << "interpolation: " << extra("interpolation")
                << "; source voxels outside the grid: " << extra("source_voxels_outside_grid") << '\n';
    }
    std::string grids;
    for (const auto& c : info.channels) grids += (grids.empty() ? "" : ", ") + c.name + " (" + c.valueType + ")";
    row("grids") << grids << '\n';
    const Vec3i d = info.box.dims();
    row("dimensions") << d.x() << " x " << d.y() << " x " << d.z() << " voxels\n";
    row("spacing") << triple(g.spacing, 4, " x ") << " mm\n";
    row("origin") << triple(g.origin, 3, ", ") << " mm (LPS, centre of voxel 0,0,0)\n";
    const bool axisAligned = g.direction.isIdentity(1e-12);
    row("direction") << (axisAligned ? "identity (axis-aligned LPS)" : "oblique") << '\n';
    if (!axisAligned) {
        for (int c = 0; c < 3; ++c) {
            row("") << "ijk"[c] << " -> " << triple(Vec3d(g.direction.col(c)), 6, ", ") << '\n';
        }
    }
    row("bounds") << "x " << fixed(info.worldBounds[0].x(), 1) << " .. " << fixed(info.worldBounds[1].x(), 1) << ", y "
                  << fixed(info.worldBounds[0].y(), 1) << " .. " << fixed(info.worldBounds[1].y(), 1) << ", z "
                  << fixed(info.worldBounds[0].z(), 1) << " .. " << fixed(info.worldBounds[1].z(), 1) << " mm\n";
    const double fraction = info.denseVoxels ? 100.0 * double(info.activeVoxels) / double(info.denseVoxels) : 0.0;
    row("voxels") << info.activeVoxels << " active of " << info.denseVoxels << " dense (" << fixed(fraction, 1)
                  << " %)\n";
    row("memory") << mib(info.memoryBytes) << " sparse, " << mib(denseBytes(info)) << " as dense float/int32 arrays\n";
    for (const auto& c : info.channels) {
        if (c.name == "label") continue;
        const std::string unit = c.name == "hu" ? info.metadata.huUnits
            : c.name == "t1"                    ? info.metadata.t1Units
                                                : info.metadata.intensityUnits;
        row(c.name.c_str()) << "min " << fixed(c.min, 1) << ", max " << fixed(c.max, 1) << ", mean " << fixed(c.mean, 1)
                            << ' ' << unit << " (active voxels)\n";
    }
    if (!info.labels.empty()) {
        os << "labels\n";
        for (const auto& l : info.labels) {
            os << "  " << std::right << std::setw(3) << l.id << "  " << std::left << std::setw(24) << l.name
               << std::right << std::setw(12) << l.voxels << " voxels " << std::setw(10) << fixed(l.volumeMl, 2)
               << " ml\n";
        }
    }
    if (info.metadata.fusion) {
        os << "registration (MR onto CT, voxhap fuse)\n";
        printFusionRecord(os, *info.metadata.fusion, "  ");
    }
    if (info.layers) {
        os << "layers along the reference path (depth from its entry):\n";
        os << "  " << std::right << std::setw(9) << "from mm" << std::setw(10) << "to mm" << std::setw(12)
           << "thickness"
           << "  tissue\n";
        for (const auto& l : *info.layers) {
            os << "  " << std::setw(9) << fixed(l.startMm, 2) << std::setw(10) << fixed(l.endMm, 2) << std::setw(12)
               << fixed(l.endMm - l.startMm, 2) << "  " << l.name << '\n';
        }
    }
}

} // namespace voxhap::tools
