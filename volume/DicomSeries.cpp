// SPDX-License-Identifier: Apache-2.0
/// @file DicomSeries.cpp
/// @brief Series grouping, slice geometry, memory cap, slab-wise sparse loading.

#include "volume/DicomSeries.h"

#include "volume/DicomHeaders.h"
#include "volume/DicomDecodeProcess.h"
#include "volume/DicomPixels.h"
#include "volume/Errors.h"
#include "volume/Grids.h"
#include "volume/SliceResample.h"
#include "volume/SliceStack.h"
#include "volume/SparseSlabs.h"
#include "volume/T1Normalisation.h"

#include <Eigen/Geometry>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>

namespace voxhap::volume {

namespace {

namespace fs = std::filesystem;

/// One 2D slice: a frame of a file, with its rescale.
struct Slice {
    std::size_t file = 0;   ///< index into the series' headers
    int frame = 0;
    Vec3d position{0, 0, 0};
    double slope = 1, intercept = 0;
};

std::string mib(std::uint64_t bytes)
{
    std::ostringstream os;
    os.precision(1);
    os << std::fixed << double(bytes) / double(1 << 20) << " MiB";
    return os.str();
}

const DicomSeriesInfo& chooseSeries(const std::vector<DicomSeriesInfo>& all, const std::string& wanted)
{
    if (wanted.empty()) {
        // Largest CT, else the largest series (the list is sorted largest first).
        for (const auto& s : all) {
            if (s.modality == "CT") return s;
        }
        return all.front();
    }
    for (const auto& s : all) {
        if (s.uid == wanted) return s;
    }
    if (std::all_of(wanted.begin(), wanted.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); })) {
        const std::size_t n = std::stoul(wanted);
        if (n >= 1 && n <= all.size()) return all[n - 1];
    }
    throw ValueError("series '" + wanted + "': not found (" + std::to_string(all.size()) +
                     " series present; give a SeriesInstanceUID or a number from 1 to " + std::to_string(all.size()) + ")");
}

/// Frames of a file decoded on demand; multi-frame files are decoded once.
class FrameSource {
public:
    explicit FrameSource(const std::vector<DicomHeader>& headers) : mHeaders(headers), mCache(headers.size()) {}

    /// The stored samples of @p s's file: decoded into @p scratch (its buffers
    /// reused slice after slice), or a multi-frame file's cached decode.
    const DicomFrames& frames(const Slice& s, DicomFrames& scratch)
    {
        const DicomFrames* frames = &scratch;
        const DicomHeader& h = mHeaders[s.file];
        if (h.frames > 1) {
            std::lock_guard<std::mutex> lock(mMutex);
            if (!mCache[s.file]) {
                auto decoded = std::make_shared<DicomFrames>();
                if (!readNativeFrames(h, *decoded)) mDecoder.decode(h.file, *decoded);
                mCache[s.file] = decoded;
            }
            frames = mCache[s.file].get(); // lives as long as this source
        } else if (!readNativeFrames(h, scratch)) {
            std::lock_guard<std::mutex> lock(mMutex); // one decoder process, one request at a time
            mDecoder.decode(h.file, scratch);
        }
        if (frames->rows != h.rows || frames->columns != h.columns || frames->frames != h.frames) {
            throw IoError(h.file.string() + ": (0028,0010) Rows / (0028,0011) Columns / (0028,0008) NumberOfFrames: "
                          "pixel data dimensions differ from the header");
        }
        return *frames;
    }

    /// Copy one frame, rescaled, into @p out (rows × columns floats); padding becomes @p air.
    void read(const Slice& s, float* out, float air)
    {
        thread_local DicomFrames scratch; // one per decoding thread
        frameToFloat(frames(s, scratch), s.frame, s.slope, s.intercept, mHeaders[s.file].padding, air, out);
    }

    const DicomHeader& header(const Slice& s) const { return mHeaders[s.file]; }

private:
    const std::vector<DicomHeader>& mHeaders;
    std::vector<std::shared_ptr<const DicomFrames>> mCache;
    DicomDecodeProcess mDecoder; // GDCM's decodes, for files not read directly
    std::mutex mMutex;
};

} // namespace

bool looksLikeDicom(const fs::path& path)
{
    std::error_code ec;
    if (fs::is_directory(path, ec)) return true;
    std::ifstream in(path, std::ios::binary);
    char magic[132] = {};
    if (!in.read(magic, sizeof magic)) return false;
    return std::string(magic + 128, 4) == "DICM";
}

namespace {

std::vector<DicomSeriesInfo> groupSeries(const std::vector<DicomHeader>& headers)
{
    std::map<std::string, DicomSeriesInfo> byUid;
    for (const DicomHeader& h : headers) {
        DicomSeriesInfo& s = byUid[h.seriesUid];
        if (s.files.empty()) {
            s.uid = h.seriesUid;
            s.modality = h.modality;
            s.description = h.seriesDescription;
            s.number = h.seriesNumber;
            s.rows = h.rows;
            s.columns = h.columns;
        }
        s.files.push_back(h.file);
        s.slices += h.frames;
    }
    std::vector<DicomSeriesInfo> all;
    for (auto& [uid, s] : byUid) all.push_back(std::move(s));
    std::stable_sort(all.begin(), all.end(), [](const DicomSeriesInfo& a, const DicomSeriesInfo& b) {
        return a.slices * a.rows * a.columns > b.slices * b.rows * b.columns;
    });
    return all;
}

/// T1-weighted intensities → T1 [ms] (physics.md §5.1); the raw values stay,
/// labelled "not normalised" with the reason, when the scan does not allow it.
void normaliseT1Weighted(Volume& v, const DicomHeader& first, const DicomOptions& options, const fs::path& dir)
{
    const FieldStrength field = first.fieldStrength ? nearestFieldStrength(*first.fieldStrength) : options.assumedField;
    try {
        applyT1wNormalisation(v, fitT1wNormalisation(v, TissueTable::builtin(), field, dir.string()));
        v.metadata().extra["t1_norm_field_source"] =
            first.fieldStrength ? "(0018,0087) MagneticFieldStrength" : "assumed: (0018,0087) absent";
    } catch (const ValueError& e) {
        v.metadata().t1Units = "T1-weighted intensity (arbitrary units, not normalised)";
        v.metadata().extra["t1_norm_refused"] = e.what();
    }
}

} // namespace

std::vector<DicomSeriesInfo> listDicomSeries(const std::vector<fs::path>& inputs)
{
    return groupSeries(scanDicomHeaders(inputs));
}

Volume loadDicom(const std::vector<fs::path>& inputs, const DicomOptions& options, DicomLoadReport* report)
{
    const auto start = std::chrono::steady_clock::now();
    const auto since = [](std::chrono::steady_clock::time_point t) {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    };
    std::vector<DicomHeader> scanned = scanDicomHeaders(inputs);
    const std::vector<DicomSeriesInfo> all = groupSeries(scanned);
    const DicomSeriesInfo& series = chooseSeries(all, options.series);

    std::vector<DicomHeader> headers;
    for (DicomHeader& h : scanned) {
        if (h.seriesUid == series.uid) headers.push_back(std::move(h));
    }
    for (DicomHeader& h : headers) completeDicomHeader(h);
    const double scanSeconds = since(start);
    double decodeSeconds = 0, sparseSeconds = 0;
    const DicomHeader& first = headers.front();
    const bool isMr = first.modality == "MR";

    // Every slice must share the first one's grid: orientation, size, pixel spacing.
    for (const DicomHeader& h : headers) checkSameGrid(first, h);
    const Vec3d row = first.rowDirection, col = first.columnDirection;
    const Vec3d normal = row.cross(col).normalized();

    std::vector<Slice> slices;
    std::vector<SlicePlacement> placements;
    for (std::size_t f = 0; f < headers.size(); ++f) {
        const DicomHeader& h = headers[f];
        for (int k = 0; k < h.frames; ++k) {
            placements.push_back({h.framePositions[std::size_t(k)], slices.size()});
            slices.push_back({f, k, h.framePositions[std::size_t(k)], h.slope, h.intercept});
        }
    }
    SliceStackGeometry stack;
    try {
        stack = orderSlices(placements, normal);
    } catch (const ValueError& e) {
        throw IoError(series.files.front().parent_path().string() + ": (0020,0032) ImagePositionPatient: " + e.what());
    }
    if (!stack.problem.empty() && first.gantryTilt != 0.0 && stack.tilted) {
        stack.problem += " ((0018,1120) GantryDetectorTilt " + std::to_string(first.gantryTilt) + " deg)";
    }
    const bool resample = !stack.problem.empty();
    if (resample && options.irregular == IrregularSlices::Refuse) {
        throw IoError(series.files.front().parent_path().string() + ": (0020,0032) ImagePositionPatient: " +
                      stack.problem + "; refusing (ask for resampling to load it on a uniform grid)");
    }

    Geometry geo;
    geo.spacing = Vec3d(first.pixelSpacing[1], first.pixelSpacing[0], 1.0);
    if (slices.size() > 1) geo.spacing[2] = stack.step;
    else if (first.sliceThickness > 0) geo.spacing[2] = first.sliceThickness; // one slice: nothing else to go by
    geo.direction.col(0) = row;
    geo.direction.col(1) = col;
    geo.direction.col(2) = normal;
    geo.origin = stack.slices.front().position;

    const int nx = first.columns, ny = first.rows;
    int nz = int(slices.size());
    if (resample) {
        const double length = (stack.slices.back().position - stack.slices.front().position).dot(normal);
        nz = int(std::lround(length / stack.step)) + 1;
    }
    const std::size_t plane = std::size_t(nx) * std::size_t(ny);
    // Worst case: every voxel active in the float grid (leaf overhead is ~1%),
    // plus one slab, plus the whole input stack when resampling.
    const std::uint64_t need = std::uint64_t(plane) * std::uint64_t(nz) * sizeof(float) +
                               std::uint64_t(plane) * SparseSlabs::kSlabSlices * sizeof(float) +
                               (resample ? std::uint64_t(plane) * slices.size() * sizeof(float) : 0);
    if (need > options.memoryCapBytes) {
        throw IoError(series.files.front().parent_path().string() + ": (0028,0010) Rows × (0028,0011) Columns × slices = " +
                      std::to_string(nx) + "×" + std::to_string(ny) + "×" + std::to_string(nz) + " voxels may need " +
                      mib(need) + ", over the memory cap of " + mib(options.memoryCapBytes));
    }

    const float background = isMr ? kAirT1 : kAirHu;
    const float airBelow = isMr ? options.airT1 : options.airHu;
    SparseSlabs sparse(background, airBelow);
    FrameSource source(headers);

    if (!resample) {
        // The slab's stored samples are decoded, then converted to floats row by
        // row straight into the grid's leaves: the slab never exists as floats.
        std::vector<DicomFrames> decoded(SparseSlabs::kSlabSlices);
        std::vector<const DicomFrames*> frames(SparseSlabs::kSlabSlices, nullptr);
        for (int k0 = 0; k0 < nz; k0 += SparseSlabs::kSlabSlices) {
            const int n = std::min(SparseSlabs::kSlabSlices, nz - k0);
            auto t = std::chrono::steady_clock::now();
            tbb::parallel_for(0, n, [&](int k) {
                frames[std::size_t(k)] = &source.frames(slices[stack.slices[std::size_t(k0 + k)].source], decoded[std::size_t(k)]);
            });
            decodeSeconds += since(t);
            t = std::chrono::steady_clock::now();
            // Integer samples (at most 32 bits) under a rescale below 1e28 stay
            // far inside float's range (2^32 · 1e28 < 3.4e38): no NaN or inf to look for.
            constexpr double kFiniteRescale = 1e28;
            bool finite = true;
            for (int k = 0; k < n; ++k) {
                const Slice& s = slices[stack.slices[std::size_t(k0 + k)].source];
                const SampleType type = frames[std::size_t(k)]->type;
                finite = finite && type != SampleType::Float32 && type != SampleType::Float64 &&
                         std::abs(s.slope) < kFiniteRescale && std::abs(s.intercept) < kFiniteRescale;
            }
            sparse.addSlabRows(
                [&](int z, int y, float* scratch) {
                    const Slice& s = slices[stack.slices[std::size_t(k0 + z)].source];
                    samplesToFloat(*frames[std::size_t(z)], s.frame, std::size_t(y) * std::size_t(nx), std::size_t(nx), s.slope,
                                   s.intercept, source.header(s).padding, background, scratch);
                    return static_cast<const float*>(scratch);
                },
                nx, ny, k0, n, finite);
            sparseSeconds += since(t);
            if (options.progress) options.progress(double(k0 + n) / nz);
        }
    } else {
        std::vector<float> slab(plane * SparseSlabs::kSlabSlices);
        std::vector<float> input(plane * slices.size());
        tbb::parallel_for(std::size_t(0), slices.size(), [&](std::size_t k) {
            source.read(slices[stack.slices[k].source], input.data() + plane * k, background);
        });
        SliceResampler resampler(stack, input.data(), nx, ny, row, col, geo.spacing.head<2>(), background);
        for (int k0 = 0; k0 < nz; k0 += SparseSlabs::kSlabSlices) {
            const int n = std::min(SparseSlabs::kSlabSlices, nz - k0);
            tbb::parallel_for(0, n, [&](int k) {
                resampler.sample(geo.origin + double(k0 + k) * geo.spacing[2] * normal, slab.data() + plane * std::size_t(k));
            });
            sparse.addSlab(slab.data(), nx, ny, k0, n);
            if (options.progress) options.progress(double(k0 + n) / nz);
        }
    }

    Volume v(geo, IndexBox{Vec3i::Zero(), Vec3i(nx - 1, ny - 1, nz - 1)});
    Volume::GridPtr grid;
    try {
        grid = sparse.finish();
    } catch (const ValueError& e) {
        throw IoError(series.files.front().parent_path().string() + ": " + e.what());
    }
    v.setGrid(isMr ? Channel::T1 : Channel::Hu, grid);

    VolumeMetadata& md = v.metadata();
    md.modality = first.modality.empty() ? "unknown" : first.modality;
    md.source = "DICOM series " + series.uid;
    md.description = first.seriesDescription;
    if (isMr) {
        const bool map = options.t1Map || first.looksLikeT1Map();
        md.t1Units = map ? "ms" : "T1-weighted intensity (arbitrary units, not normalised)";
        md.extra["t1_kind"] = map ? "T1 map" : "T1-weighted";
        if (!map && options.normaliseT1Weighted) normaliseT1Weighted(v, first, options, series.files.front().parent_path());
    }
    md.extra["series_uid"] = series.uid;
    md.extra["slices"] = std::to_string(slices.size());
    std::ostringstream air;
    air << airBelow;
    md.extra["air_below"] = air.str();
    if (resample) md.extra["resampled"] = stack.problem;

    if (report) {
        report->series = series;
        report->allSeries = all;
        report->denseVoxels = v.indexBox().voxelCount();
        report->activeVoxels = std::int64_t(grid->activeVoxelCount());
        report->memoryBytes = grid->memUsage();
        report->resampled = resample;
        report->irregularity = stack.problem;
        report->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        report->scanSeconds = scanSeconds;
        report->decodeSeconds = decodeSeconds;
        report->sparseSeconds = sparseSeconds;
    }
    return v;
}

} // namespace voxhap::volume
