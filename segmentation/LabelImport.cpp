// SPDX-License-Identifier: Apache-2.0
/// @file LabelImport.cpp
/// @brief Mapping files and nearest-neighbour resampling of imported label maps.

#include "segmentation/LabelImport.h"

#include "core/BoundedRead.h"
#include "core/Errors.h"
#include "core/JsonFields.h"
#include "volume/Grids.h"

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <fstream>
#include <mutex>
#include <sstream>

namespace voxhap::segmentation {

namespace {

LabelMapping readLabelMapping(const std::string& text, const std::string& origin, const volume::TissueTable& table)
{
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {
        std::string why = e.what();
        std::replace(why.begin(), why.end(), '\n', ' ');
        throw ValueError(origin + ": not JSON (" + why + ")");
    }
    LabelMapping m;
    m.origin = origin;
    JsonFields f(j, origin, "");
    if (!f.has("schema") || f.raw("schema") != "voxhap.label-mapping/1") {
        f.fail("schema", "must be \"voxhap.label-mapping/1\"");
    }
    if (f.has("file")) {
        if (!f.raw("file").is_string() || f.raw("file").get<std::string>().empty())
            f.fail("file", "must be a file name");
        m.file = f.raw("file").get<std::string>();
    }
    if (!f.has("labels") || !f.raw("labels").is_object() || f.raw("labels").empty()) {
        f.fail("labels", "must be a non-empty object from label-map values to tissue names or ids");
    }
    for (const auto& [key, value] : f.raw("labels").items()) {
        const std::string field = "labels." + key;
        std::int64_t v = 0;
        std::size_t used = 0;
        try {
            v = std::stoll(key, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used != key.size() || key.empty())
            throw ValueError(origin + ": " + field + ": the key must be an integer label value");
        if (v == 0) throw ValueError(origin + ": " + field + ": 0 means unlabelled and cannot be mapped");
        const volume::Tissue* t = nullptr;
        if (value.is_string())
            t = table.find(value.get<std::string>());
        else if (value.is_number_integer())
            t = table.find(int(value.get<std::int64_t>()));
        if (!t)
            throw ValueError(origin + ": " + field + ": " + value.dump() + " is not a tissue name or id of the table");
        m.tissueOf[v] = std::int32_t(t->id);
    }
    return m;
}

} // namespace

LabelMapping parseLabelMapping(const std::string& text, const std::string& origin, const volume::TissueTable& table)
{
    // Every nlohmann::json exception of the walk (a value of an unexpected type) on one line.
    return JsonFields::guarded(origin, [&] { return readLabelMapping(text, origin, table); });
}

LabelMapping loadLabelMapping(const std::filesystem::path& file, const volume::TissueTable& table)
{
    // A regular file within the size limit: not a FIFO, /dev/zero or a huge file.
    LabelMapping m = parseLabelMapping(readBoundedFile(file, "label mapping"), file.string(), table);
    if (!m.file.empty() && m.file.is_relative()) m.file = file.parent_path() / m.file;
    return m;
}

std::vector<std::int32_t> resampleLabels(const volume::Volume& labels, const LabelMapping& mapping,
    const volume::Volume& target, const Lattice& lat, const std::string& file)
{
    // A voxhap label grid, else the values of whatever one channel the reader filled.
    volume::FloatGrid::ConstPtr values;
    volume::LabelGrid::ConstPtr ids = volume::labelGrid(labels);
    if (!ids) values = volume::huGrid(labels) ? volume::huGrid(labels) : volume::t1Grid(labels);
    if (!ids && !values) throw ValueError(file + ": the label map holds no grid");

    // Index-to-index map: label-map index = M · target index + c.
    const auto toLabel = [&](const Vec3d& ijk) { return labels.worldToIndex(target.indexToWorld(ijk)); };
    std::vector<std::int32_t> out(lat.size(), -1);
    std::mutex errorMutex;
    std::string error;
    std::atomic<bool> failed{false};
    tbb::parallel_for(0, lat.dims.z(), [&](int k) {
        auto idAcc = ids ? std::optional(ids->getConstAccessor()) : std::nullopt;
        auto valueAcc = values ? std::optional(values->getConstAccessor()) : std::nullopt;
        for (int j = 0; j < lat.dims.y() && !failed; ++j) {
            for (int i = 0; i < lat.dims.x(); ++i) {
                const Vec3d q = toLabel((lat.origin + Vec3i(i, j, k)).cast<double>());
                const openvdb::Coord c(int(std::lround(q.x())), int(std::lround(q.y())), int(std::lround(q.z())));
                std::int64_t v = 0;
                if (idAcc) {
                    v = idAcc->getValue(c);
                } else {
                    const float x = valueAcc->getValue(c);
                    if (!valueAcc->isValueOn(c)) continue; // outside the map, or its inactive background
                    if (!std::isfinite(x) || x != std::round(x)) {
                        std::lock_guard lock(errorMutex);
                        error = "data: value " + std::to_string(x) + " at voxel " + std::to_string(c.x()) + "," +
                            std::to_string(c.y()) + "," + std::to_string(c.z()) + " is not an integer label";
                        failed = true;
                        break;
                    }
                    v = std::int64_t(x);
                }
                if (v == 0) continue;
                const auto it = mapping.tissueOf.find(v);
                if (it == mapping.tissueOf.end()) {
                    std::lock_guard lock(errorMutex);
                    error = "value " + std::to_string(v) + " is not in the label mapping " + mapping.origin;
                    failed = true;
                    break;
                }
                out[lat.index(i, j, k)] = it->second;
            }
        }
    });
    if (failed) throw ValueError(file + ": " + error);
    return out;
}

std::int64_t applyImported(std::vector<std::int32_t>& ids, const std::vector<std::int32_t>& imported)
{
    std::int64_t changed = 0;
    for (std::size_t n = 0; n < ids.size(); ++n) {
        if (imported[n] >= 0 && ids[n] != imported[n]) {
            ids[n] = imported[n];
            ++changed;
        }
    }
    return changed;
}

} // namespace voxhap::segmentation
