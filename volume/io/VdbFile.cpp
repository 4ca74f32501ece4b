// SPDX-License-Identifier: Apache-2.0
/// @file VdbFile.cpp
/// @brief .vdb reading and writing through openvdb::io::File.

#include "volume/io/VdbFile.h"

#include "core/AtomicFile.h"
#include "core/Errors.h"
#include "volume/Grids.h"

#include <openvdb/io/File.h>

#include <fstream>

namespace voxhap::volume {

namespace {

constexpr const char* kPrefix = "voxhap.";
constexpr const char* kFormatKey = "voxhap.format";
constexpr int kFormatVersion = 1;

void putString(openvdb::MetaMap& meta, const std::string& key, const std::string& value)
{
    meta.insertMeta(kPrefix + key, openvdb::StringMetadata(value));
}

std::string getString(const openvdb::MetaMap& meta, const std::string& key, const std::string& fallback = {})
{
    if (auto m = meta.getMetadata<openvdb::StringMetadata>(kPrefix + key)) return m->value();
    return fallback;
}

} // namespace

void saveVdb(const Volume& v, const std::filesystem::path& file)
{
    initializeOpenVdb();
    openvdb::GridCPtrVec grids;
    for (Channel c : kChannels) {
        if (v.has(c)) grids.push_back(v.grid(c));
    }
    for (const auto& [name, g] : v.derivedGrids()) grids.push_back(g);
    if (grids.empty()) throw IoError(file.string() + ": the volume holds no grid to save");

    openvdb::MetaMap meta;
    meta.insertMeta(kFormatKey, openvdb::Int32Metadata(kFormatVersion));
    const auto& md = v.metadata();
    putString(meta, "modality", md.modality);
    putString(meta, "source", md.source);
    putString(meta, "description", md.description);
    putString(meta, "hu_units", md.huUnits);
    putString(meta, "t1_units", md.t1Units);
    putString(meta, "intensity_units", md.intensityUnits);
    putString(meta, "mr_weighting", md.mrWeighting);
    for (const auto& [key, value] : md.extra) putString(meta, "extra." + key, value);
    meta.insertMeta("voxhap.index_min", openvdb::Vec3IMetadata(openvdb::Vec3i(v.indexBox().min.data())));
    meta.insertMeta("voxhap.index_max", openvdb::Vec3IMetadata(openvdb::Vec3i(v.indexBox().max.data())));

    writeAtomically(file, [&](const std::filesystem::path& tmp) {
        openvdb::io::File out(tmp.string());
        out.write(grids, meta);
        out.close();
    });
}

Volume loadVdb(const std::filesystem::path& file)
{
    initializeOpenVdb();
    if (!std::filesystem::is_regular_file(file)) throw IoError(file.string() + ": no such file");
    openvdb::io::File in(file.string());
    openvdb::GridPtrVecPtr grids;
    openvdb::MetaMap::Ptr meta;
    try {
        in.open(false); // no delayed loading: the file may change or vanish afterwards
        grids = in.getGrids();
        meta = in.getMetadata();
        in.close();
    } catch (const openvdb::Exception& e) {
        throw IoError(file.string() + ": not a readable OpenVDB file (" + std::string(e.what()) + ")");
    } catch (const std::exception& e) {
        throw IoError(file.string() + ": cannot read (" + std::string(e.what()) + ")");
    }

    std::array<openvdb::GridBase::Ptr, kChannels.size()> byChannel{};
    std::vector<openvdb::GridBase::Ptr> derived; // float grids besides the channels, e.g. distance fields
    std::string others;
    for (const auto& g : *grids) {
        bool matched = false;
        for (Channel c : kChannels) {
            if (g->getName() != channelName(c)) continue;
            if (byChannel[std::size_t(c)]) throw IoError(file.string() + ": grid '" + g->getName() + "' appears twice");
            byChannel[std::size_t(c)] = g;
            matched = true;
        }
        if (matched) continue;
        others += (others.empty() ? "" : ", ") + g->getName();
        if (g->isType<FloatGrid>()) derived.push_back(g);
    }
    openvdb::GridBase::Ptr first;
    for (const auto& g : byChannel) {
        if (g && !first) first = g;
    }
    if (!first) {
        throw IoError(file.string() + ": no grid named hu, t1, label or intensity" +
            (others.empty() ? "" : " (found: " + others + ")"));
    }
    for (const auto& g : byChannel) {
        if (g && g->transform() != first->transform()) {
            throw IoError(file.string() + ": grid '" + g->getName() + "' has a different transform from '" +
                first->getName() + "'");
        }
    }
    if (!first->transform().isLinear())
        throw IoError(file.string() + ": grid '" + first->getName() + "' has a non-linear transform");

    IndexBox box;
    auto lo = meta->getMetadata<openvdb::Vec3IMetadata>("voxhap.index_min");
    auto hi = meta->getMetadata<openvdb::Vec3IMetadata>("voxhap.index_max");
    if (lo && hi) {
        box.min = Vec3i(lo->value().x(), lo->value().y(), lo->value().z());
        box.max = Vec3i(hi->value().x(), hi->value().y(), hi->value().z());
    } else { // a foreign file: the union of the active bounding boxes
        openvdb::CoordBBox bb;
        for (const auto& g : byChannel) {
            if (g) bb.expand(g->evalActiveVoxelBoundingBox());
        }
        box.min = fromCoord(bb.min());
        box.max = fromCoord(bb.max());
    }

    Volume v(first->transform().copy(), box);
    for (Channel c : kChannels) {
        if (auto& g = byChannel[std::size_t(c)]) {
            try {
                v.setGrid(c, g);
            } catch (const ValueError& e) {
                throw IoError(file.string() + ": " + e.what());
            }
        }
    }
    for (const auto& g : derived) {
        if (g->transform() != first->transform()) {
            throw IoError(file.string() + ": grid '" + g->getName() + "' has a different transform from '" +
                first->getName() + "'");
        }
        if (v.derived(g->getName())) throw IoError(file.string() + ": grid '" + g->getName() + "' appears twice");
        v.setDerived(g->getName(), g);
    }
    auto& md = v.metadata();
    md.modality = getString(*meta, "modality");
    md.source = getString(*meta, "source", file.filename().string());
    md.description = getString(*meta, "description");
    md.huUnits = getString(*meta, "hu_units", "HU");
    md.t1Units = getString(*meta, "t1_units", "ms");
    md.intensityUnits = getString(*meta, "intensity_units", "arbitrary units");
    md.mrWeighting = getString(*meta, "mr_weighting");
    const std::string extraPrefix = std::string(kPrefix) + "extra.";
    for (auto it = meta->beginMeta(); it != meta->endMeta(); ++it) {
        if (it->first.rfind(extraPrefix, 0) == 0) {
            if (auto s = meta->getMetadata<openvdb::StringMetadata>(it->first)) {
                md.extra[it->first.substr(extraPrefix.size())] = s->value();
            }
        }
    }
    return v;
}

} // namespace voxhap::volume
