// SPDX-License-Identifier: Apache-2.0
/// @file Segmentation.cpp
/// @brief The segmentation pipeline and the label summary.

#include "segmentation/Segmentation.h"

#include "core/Errors.h"
#include "segmentation/CtSegmentation.h"
#include "segmentation/DistanceField.h"
#include "segmentation/MrSegmentation.h"
#include "segmentation/lattice/DenseGrids.h"
#include "volume/Grids.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
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

// Bytes per voxel of the working arrays at each step's peak, counted from the
// code (1 per mask, 4 per float or id array), and of a sparse grid's active voxel
// (4 bytes a value, plus leaf masks and nodes: about 5 % [measured on the CT's grids]).
constexpr double kCtBodyStep = 5.0;   // smoothing classes, the foreground and three masks of bodyMask
constexpr double kCtRulesStep = 14.0; // HU, region ids (then labels), seven masks at the enhanced step
constexpr double kMrStep = 22.0;      // values, labels, a distance array, five masks, three value lists
constexpr double kImportStep = 12.0;  // labels, imported ids, the map's resampling
constexpr double kGridPerActive = 4.2;
constexpr double kFieldStep = 9.0; // per voxel of a distance field's box: a mask and two float arrays
// Whatever the size: the worker threads' stacks and arenas, the run lists and
// per-slice buffers, the allocator's slack [measured: 16 MiB on a 2 mm phantom].
constexpr double kFixedBytes = 32.0 * (1 << 20);

double mib(std::uint64_t b) { return double(b) / double(1 << 20); }

/// The voxels the CT rules' box can hold: the HU grid's active box widened by the
/// smoothing kernel and the canal margin (a body voxel has active voxels in its
/// kernel), clamped to the lattice, the slice axis whole (CtSegmentation.cpp bodyBox).
double ctBoxVoxels(const volume::Volume& v, const Lattice& lat)
{
    const openvdb::CoordBBox active = volume::huGrid(v)->evalActiveVoxelBoundingBox();
    if (active.empty()) return 0.0;
    double n = 1.0;
    for (int a = 0; a < 3; ++a) {
        if (a == lat.sliceAxis) {
            n *= lat.dims[a];
            continue;
        }
        const int m = int(std::ceil((3.0 + 7.0) / lat.spacing[a])) + 4; // 3σ of 1 mm, 7 mm closing, and rounding
        const int lo = std::max(lat.origin[a], active.min()[a] - m);
        const int hi = std::min(lat.origin[a] + lat.dims[a] - 1, active.max()[a] + m);
        n *= std::max(0, hi - lo + 1);
    }
    return n;
}

std::uint64_t gridBytes(const volume::Volume& v)
{
    std::uint64_t b = 0;
    for (const volume::Channel c :
        {volume::Channel::Hu, volume::Channel::T1, volume::Channel::Intensity, volume::Channel::Label}) {
        if (v.has(c)) b += v.grid(c)->memUsage();
    }
    return b;
}

/// Refuse, in one line, a need over the cap.
void checkCap(
    const volume::Volume& v, const SegmentOptions& o, std::uint64_t input, std::uint64_t need, const std::string& what)
{
    if (!o.memoryCapBytes || input + need <= o.memoryCapBytes) return;
    char buf[512];
    std::snprintf(buf, sizeof buf,
        "%s: %s needs about %.0f MiB of working memory beside the volume's %.0f MiB, over the memory cap of %.0f MiB",
        v.metadata().source.c_str(), what.c_str(), mib(need), mib(input), mib(o.memoryCapBytes));
    throw ValueError(buf);
}

} // namespace

std::uint64_t workingBytes(const volume::Volume& v, const SegmentOptions& o)
{
    const Lattice lat = Lattice::of(v);
    const double n = double(lat.size());
    double bytes = 0, labelled = n;
    if (o.automatic && v.has(volume::Channel::Hu)) {
        const double box = ctBoxVoxels(v, lat);
        labelled = box;
        bytes = std::max(kCtBodyStep * n, kCtRulesStep * box);
    } else if (o.automatic && (v.has(volume::Channel::T1) || v.has(volume::Channel::Intensity))) {
        bytes = kMrStep * n;
    } else {
        bytes = 4.0 * n; // the labels
    }
    if (o.imported) bytes = std::max(bytes, kImportStep * n);
    // Then the labels stay while their grid is built beside them.
    bytes = std::max(bytes, (4.0 + kGridPerActive) * labelled);
    return std::uint64_t(bytes + kFixedBytes);
}

SegmentReport segment(volume::Volume& v, const volume::TissueTable& table, const SegmentOptions& o)
{
    const auto start = std::chrono::steady_clock::now();
    const auto step = [&](const std::string& s) {
        if (o.progress) o.progress(-1.0, s); // the steps' count is not known ahead
    };
    SegmentReport report;
    report.inputBytes = gridBytes(v);
    report.workingBytes = workingBytes(v, o);
    checkCap(v, o, report.inputBytes, report.workingBytes, "segmentation");
    const Lattice whole = Lattice::of(v);
    Lattice lat = whole; // the labels' box: automatic CT labels cover the body's box only
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
        const MrContrast c = v.metadata().mrWeighting == volume::MrWeightingKind::T1Weighted ? MrContrast::T1Weighted
                                                                                             : MrContrast::Unknown;
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
        std::vector<std::int32_t> imported =
            resampleLabels(*o.imported->labels, o.imported->mapping, v, lat, o.imported->file);
        report.importedVoxels =
            std::int64_t(std::count_if(imported.begin(), imported.end(), [](std::int32_t x) { return x >= 0; }));
        for (const auto& [mapped, kept] : o.imported->mapping.keepAutomatic) {
            for (std::size_t n = 0; n < imported.size(); ++n) {
                if (imported[n] == mapped && labels[n] == kept) imported[n] = -1;
            }
        }
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
    // The label grid first, then each field: the fields' boxes are known now, and
    // the fields made so far stay beside the next one's working arrays.
    std::vector<std::pair<std::string, Lattice>> fields;
    {
        const double labelArray = 4.0 * double(lat.size());
        double grids = kGridPerActive * double(lat.size()), need = labelArray + grids;
        for (const std::string& name : critical) {
            const volume::Tissue& t = table.at(name);
            if (!present[std::size_t(t.id)]) continue;
            const Lattice box = distanceFieldBox(lat, labels, t.id, o.distanceBandMm, whole);
            fields.emplace_back(name, box);
            need = std::max(need, labelArray + grids + kFieldStep * double(box.size()));
            grids += kGridPerActive * double(box.size());
        }
        report.workingBytes =
            std::max(report.workingBytes, std::uint64_t(std::max(need, labelArray + grids) + kFixedBytes));
        checkCap(v, o, report.inputBytes, report.workingBytes, "segmentation with its distance fields");
    }
    step("label grid");
    v.setGrid(volume::Channel::Label, labelGridFrom(lat, labels));
    for (const auto& [name, box] : fields) {
        step("distance field " + name);
        v.setDerived(
            distanceFieldName(name), signedDistanceField(lat, labels, table.at(name).id, o.distanceBandMm, whole));
        report.distanceFields.push_back(distanceFieldName(name));
    }
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
