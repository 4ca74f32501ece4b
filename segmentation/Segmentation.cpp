// SPDX-License-Identifier: Apache-2.0
/// @file Segmentation.cpp
/// @brief The segmentation pipeline and the label summary.

#include "segmentation/Segmentation.h"

#include "segmentation/CtSegmentation.h"
#include "segmentation/DenseGrids.h"
#include "segmentation/DistanceField.h"
#include "segmentation/MrSegmentation.h"
#include "core/Errors.h"
#include "volume/Grids.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <map>
#include <utility>

namespace voxhap::segmentation {

namespace {

/// @p labels over the sub-box @p lat placed in @p whole, air elsewhere.
std::vector<std::int32_t> embedLabels(const Lattice& lat, const std::vector<std::int32_t>& labels, const Lattice& whole)
{
    std::vector<std::int32_t> out(whole.size(), volume::kAirLabel);
    const Vec3i off = lat.origin - whole.origin;
    for (int k = 0; k < lat.dims.z(); ++k) {
        for (int j = 0; j < lat.dims.y(); ++j) {
            std::copy_n(labels.begin() + std::ptrdiff_t(lat.index(0, j, k)), lat.dims.x(),
                out.begin() + std::ptrdiff_t(whole.index(off.x(), off.y() + j, off.z() + k)));
        }
    }
    return out;
}

} // namespace

SegmentReport segment(volume::Volume& v, const volume::TissueTable& table, const SegmentOptions& o)
{
    const auto start = std::chrono::steady_clock::now();
    const auto step = [&](const std::string& s) {
        if (o.progress) o.progress(-1.0, s); // the steps' count is not known ahead
    };
    const Lattice whole = Lattice::of(v);
    Lattice lat = whole; // the labels' box: automatic CT labels cover the body's box only
    SegmentReport report;
    std::vector<std::int32_t> labels;
    const auto automatic = [&](AutomaticLabels a) {
        lat = a.lattice;
        labels = std::move(a.labels);
        report.notes = std::move(a.notes);
        report.bodyWidthMm = a.extent.widestMm();
        report.torsoFraction = a.extent.bodySlices ? double(a.extent.torsoSlices) / double(a.extent.bodySlices) : 0.0;
    };
    if (o.automatic && v.has(volume::Channel::Hu)) {
        step("CT labels");
        report.method = "ct";
        automatic(segmentCt(v, lat, *volume::huGrid(v), table));
    } else if (o.automatic && v.has(volume::Channel::T1)) {
        step("MR labels");
        report.method = "mr";
        // The t1 grid holds T1 in ms; files written before the intensity grid
        // existed may hold normalised T1-weighted values ("normalised" units).
        const MrContrast c = v.metadata().t1Units == "ms" ? MrContrast::T1Ms : MrContrast::T1Weighted;
        automatic(segmentMr(v, lat, toDense(lat, *volume::t1Grid(v)), c, table));
    } else if (o.automatic && v.has(volume::Channel::Intensity)) {
        step("MR labels");
        report.method = "mr";
        // A T1-weighted series that could not be normalised still has bright fat;
        // any other weighting says nothing about fat against muscle.
        const MrContrast c = v.metadata().mrWeighting == "T1-weighted" ? MrContrast::T1Weighted : MrContrast::Unknown;
        automatic(segmentMr(v, lat, toDense(lat, *volume::intensityGrid(v)), c, table));
    } else if (v.has(volume::Channel::Label)) {
        report.method = "existing";
        labels = toDense(lat, *volume::labelGrid(v));
    } else if (o.imported) {
        report.method = "imported";
        labels.assign(lat.size(), volume::kAirLabel);
    } else {
        throw ValueError(
            v.metadata().source + ": nothing to segment: no hu, t1, intensity or label grid and no imported label map");
    }
    if (o.imported) {
        step("imported labels");
        if (lat.dims != whole.dims) { // an imported map may label voxels anywhere in the volume
            labels = embedLabels(lat, labels, whole);
            lat = whole;
        }
        const std::vector<std::int32_t> imported =
            resampleLabels(*o.imported->labels, o.imported->mapping, v, lat, o.imported->file);
        report.importedVoxels =
            std::int64_t(std::count_if(imported.begin(), imported.end(), [](std::int32_t x) { return x >= 0; }));
        applyImported(labels, imported);
        if (report.method == "existing") report.method = "imported";
    }

    std::vector<std::string> critical = o.critical;
    if (critical.empty()) {
        for (const auto& t : table.tissues()) {
            if (t.critical) critical.push_back(t.name);
        }
    }
    std::vector<std::uint8_t> present(std::size_t(table.maxId()) + 1, 0);
    for (std::int32_t x : labels) {
        if (x >= 0 && x <= table.maxId()) present[std::size_t(x)] = 1;
    }
    for (const std::string& name : critical) {
        const volume::Tissue& t = table.at(name);
        if (!present[std::size_t(t.id)]) continue;
        step("distance field " + name);
        v.setDerived(distanceFieldName(name), signedDistanceField(lat, labels, t.id, o.distanceBandMm, whole));
        report.distanceFields.push_back(distanceFieldName(name));
    }
    step("label grid");
    v.setGrid(volume::Channel::Label, labelGridFrom(lat, labels));
    report.labels = summarizeLabels(v, table);
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
}

std::vector<LabelSummary> summarizeLabels(const volume::Volume& v, const volume::TissueTable& table)
{
    std::vector<LabelSummary> out;
    const auto grid = volume::labelGrid(v);
    if (!grid) return out;
    struct Acc {
        std::int64_t n = 0;
        openvdb::CoordBBox box;
    };
    std::map<int, Acc> acc;
    for (auto it = grid->cbeginValueOn(); it; ++it) {
        Acc& a = acc[*it];
        openvdb::CoordBBox b;
        it.getBoundingBox(b);
        a.n += std::int64_t(it.getVoxelCount());
        a.box.expand(b);
    }
    const double voxelMl = v.geometry().spacing.prod() * 1e-3;
    for (const auto& [id, a] : acc) {
        if (id == volume::kAirLabel) continue;
        LabelSummary s;
        s.id = id;
        s.name = table.find(id) ? table.find(id)->name : "unknown";
        s.voxels = a.n;
        s.ml = double(a.n) * voxelMl;
        Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
        for (int c = 0; c < 8; ++c) {
            const Vec3d ijk((c & 1 ? a.box.max() : a.box.min()).x(), (c & 2 ? a.box.max() : a.box.min()).y(),
                (c & 4 ? a.box.max() : a.box.min()).z());
            const Vec3d w = v.indexToWorld(ijk);
            lo = lo.cwiseMin(w);
            hi = hi.cwiseMax(w);
        }
        s.bounds = {lo, hi};
        out.push_back(s);
    }
    return out;
}

} // namespace voxhap::segmentation
