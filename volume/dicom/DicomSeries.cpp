// SPDX-License-Identifier: Apache-2.0
/// @file DicomSeries.cpp
/// @brief The series table, the default choice, 4D volumes, slice geometry,
/// the memory cap and slab-wise sparse loading.

#include "volume/dicom/DicomSeries.h"

#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/detail/SparseSlabs.h"
#include "volume/dicom/DicomHeaders.h"
#include "volume/dicom/detail/DicomDecodeProcess.h"
#include "volume/dicom/detail/DicomMosaic.h"
#include "volume/dicom/detail/DicomPixels.h"
#include "volume/dicom/detail/DicomVolumes.h"
#include "volume/dicom/detail/SliceResample.h"
#include "volume/dicom/detail/SliceStack.h"
#include "volume/dicom/detail/StoredPrecision.h"
#include "volume/io/GzipFile.h"

#include <Eigen/Geometry>
#include <fcntl.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

namespace voxhap::volume {

namespace {

namespace fs = std::filesystem;

std::string mib(std::uint64_t bytes)
{
    std::ostringstream os;
    os.precision(1);
    os << std::fixed << double(bytes) / double(1 << 20) << " MiB";
    return os.str();
}

/// A slice with where to find it in the stored image: a frame, or a mosaic's tile.
struct Slice {
    std::size_t file = 0;   ///< index into the series' headers
    int frame = 0;          ///< stored frame
    int row0 = 0, col0 = 0; ///< first pixel in the stored frame (a mosaic's tile)
    Vec3d position{0, 0, 0};
    double slope = 1, intercept = 0;
};

/// The series' slices that make up the chosen volume, with the geometry checks done.
struct Plan {
    std::vector<DicomHeader> headers; ///< of the files in the volume
    std::vector<Slice> slices;        ///< of the volume
    SliceStackGeometry stack;         ///< ordered along the normal
    Vec3d row{1, 0, 0}, col{0, 1, 0}, normal{0, 0, 1};
    std::size_t volume = 0; ///< from 1; 0 for a series of one volume
};

/// "axial", "sagittal" or "coronal" by the slice normal's largest LPS
/// component, "… oblique" beyond 10° from that axis [chosen: the common
/// radiological sense of an oblique plane].
std::string orientationName(const Vec3d& normal)
{
    Vec3d a = normal.cwiseAbs();
    int axis = 0;
    a.maxCoeff(&axis);
    static const char* kNames[] = {"sagittal", "coronal", "axial"};
    const double cos10 = std::cos(10.0 * kPi / 180.0);
    return std::string(kNames[axis]) + (a[axis] < cos10 ? " oblique" : "");
}

/// The fields the MR weighting rule reads, from a file's scanned header.
MrSequenceFields sequenceFields(const DicomHeader& h)
{
    MrSequenceFields f;
    f.scanningSequence = h.value(0x0018, 0x0020);
    f.sequenceVariant = h.value(0x0018, 0x0021);
    f.scanOptions = h.value(0x0018, 0x0022);
    f.sequenceName = h.value(0x0018, 0x0024);
    if (f.sequenceName.empty()) f.sequenceName = h.value(0x0018, 0x9005);
    f.imageType = h.imageType;
    f.description = h.seriesDescription;
    f.protocolName = h.value(0x0018, 0x1030);
    const auto num = [&h](std::uint16_t g, std::uint16_t e) -> std::optional<double> {
        const std::string v = h.value(g, e);
        char* end = nullptr;
        const double d = std::strtod(v.c_str(), &end);
        if (v.empty() || end != v.c_str() + v.size() || !std::isfinite(d)) return std::nullopt;
        return d;
    };
    f.repetitionTimeMs = num(0x0018, 0x0080);
    f.echoTimeMs = num(0x0018, 0x0081);
    f.inversionTimeMs = num(0x0018, 0x0082);
    f.flipAngleDeg = num(0x0018, 0x1314);
    f.bValue = h.key.bValue;
    f.source = "DICOM headers of " + h.file.filename().string();
    return f;
}

/// The slices of volume @p volume (from 1; 0 = the only one) of a series.
std::vector<Slice> volumeSlices(const std::vector<DicomHeader>& headers, const DicomVolumeSet& set, std::size_t volume)
{
    const std::vector<DicomSlice> all = seriesSlices(headers);
    const std::vector<std::size_t>& members = set.volumes[volume == 0 ? 0 : volume - 1];
    std::vector<Slice> out;
    for (std::size_t i : members) {
        const DicomSlice& d = all[i];
        Slice s;
        s.file = d.file;
        s.position = d.position;
        s.slope = d.slope;
        s.intercept = d.intercept;
        const DicomHeader& h = headers[d.file];
        if (h.mosaicImages > 0) {
            s.frame = 0;
            mosaicTileOrigin(h, d.frame, s.row0, s.col0);
        } else {
            s.frame = d.frame;
        }
        out.push_back(s);
    }
    return out;
}

/// Is @p s (a damaged file) part of series @p uid, whose files lie in @p dirs?
/// By its SeriesInstanceUID when the walk got that far; otherwise a damaged
/// file in the same folder counts, for a missing slice must not pass unseen.
bool damagedFileOf(const DicomSkippedFile& s, const std::string& uid, const std::set<fs::path>& dirs)
{
    if (s.category != "damaged") return false;
    if (!s.seriesUid.empty()) return s.seriesUid == uid;
    return dirs.count(s.file.parent_path()) > 0;
}

/// Everything about one series under @p o: its table row, and, when it
/// loads, its plan. Problems go to info.problem, never thrown.
struct SeriesWork {
    DicomSeriesInfo info;
    std::vector<DicomHeader> headers;  ///< completed (skipBad: without the bad ones)
    std::vector<DicomSkippedFile> bad; ///< files left out under skipBad
    std::optional<DicomVolumeSet> volumes;
    std::optional<Plan> plan;
};

void studySeries(SeriesWork& w, std::vector<DicomHeader> headers, const std::vector<DicomSkippedFile>& skipped,
    const DicomOptions& o, const std::map<std::string, std::string>& inflatedFrom = {})
{
    DicomSeriesInfo& info = w.info;
    const fs::path folder = headers.front().file.parent_path();
    // The folders the user's files are in (an inflated .dcm.gz counts where its original lies).
    std::set<fs::path> dirs;
    for (const auto& h : headers) {
        const auto it = inflatedFrom.find(h.file.string());
        dirs.insert(it == inflatedFrom.end() ? h.file.parent_path() : fs::path(it->second).parent_path());
    }
    for (const auto& s : skipped) {
        if (damagedFileOf(s, info.uid, dirs)) {
            ++info.damagedFiles;
            w.bad.push_back(s);
        }
    }
    // Complete the geometry of every file; a file that fails is damaged too.
    std::vector<DicomHeader> done;
    for (DicomHeader& h : headers) {
        try {
            completeDicomHeader(h);
            done.push_back(std::move(h));
        } catch (const IoError& e) {
            ++info.damagedFiles;
            w.bad.push_back({h.file, "damaged", e.what(), info.uid});
        }
    }
    if (!w.bad.empty() && !o.skipBad) {
        info.problem = w.bad.front().reason +
            (w.bad.size() > 1 ? " (and " + std::to_string(w.bad.size() - 1) + " more)" : "") +
            "; --skip-bad loads the rest of the series";
    }
    if (done.empty()) {
        if (info.problem.empty()) info.problem = folder.string() + ": no readable image in the series";
        return;
    }
    const DicomHeader& first = done.front();
    info.rows = first.rows;
    info.columns = first.columns;
    info.slices = 0;
    for (const auto& h : done) info.slices += h.frames;
    const Vec3d normal = first.rowDirection.cross(first.columnDirection).normalized();
    info.orientation = orientationName(normal);
    info.spacing = Vec3d(first.pixelSpacing[1], first.pixelSpacing[0], 0.0);
    if (first.modality == "MR") {
        const MrWeighting mw = classifyMrWeighting(sequenceFields(first));
        info.weighting = mw.name;
        info.weightingReason = mw.reason;
    }
    // The finest digit stored in any file sets the tolerances (StoredPrecision.h).
    double positionUnit = 0, orientationUnit = 0;
    for (const DicomHeader& h : done) {
        if (h.positionUnit > 0 && (positionUnit == 0 || h.positionUnit < positionUnit)) positionUnit = h.positionUnit;
        if (h.orientationUnit > 0 && (orientationUnit == 0 || h.orientationUnit < orientationUnit))
            orientationUnit = h.orientationUnit;
    }
    const double positionTolerance = positionToleranceMm(positionUnit);
    const double directionTol = directionTolerance(orientationUnit);
    w.volumes = splitVolumes(seriesSlices(done), done, positionTolerance);
    const DicomVolumeSet& set = *w.volumes;
    info.volumes = set.count();
    info.volumeShape = set.problem.empty() ? set.shape() : "";
    info.volumeSummary = set.summary();
    info.separatedBy = set.separatedBy;
    w.headers = std::move(done);
    const std::string where = folder.string() + ": series " + std::to_string(info.index) +
        (info.number.empty() ? "" : " (SeriesNumber " + info.number + ")");
    if (!set.problem.empty()) {
        info.volumes = 0;
        if (info.problem.empty()) info.problem = where + ": " + set.problem;
        return;
    }
    std::size_t volume = 0;
    if (set.count() > 1) {
        if (o.volume == 0) {
            if (info.problem.empty()) {
                info.problem = where + " holds " + set.shape() + " (by " + set.separatedBy + "; " + set.summary() +
                    "): load one with --volume 1.." + std::to_string(set.count());
            }
        } else if (o.volume > set.count()) {
            if (info.problem.empty()) {
                info.problem = where + " holds " + std::to_string(set.count()) + " volumes; --volume " +
                    std::to_string(o.volume) + " does not exist";
            }
        } else {
            volume = o.volume;
        }
    } else if (o.volume > 1 && info.problem.empty()) {
        info.problem = where + " holds one volume; --volume " + std::to_string(o.volume) + " does not exist";
    }
    const std::size_t shown = volume == 0 ? 1 : volume;
    info.voxels = std::int64_t(info.rows) * info.columns * std::int64_t(set.volumes[shown - 1].size());
    if (set.count() > 1 && volume == 0) {
        // The table still shows a slice step: the first volume's.
        std::vector<SlicePlacement> placements;
        const std::vector<Slice> firstVolume = volumeSlices(w.headers, set, 1);
        for (std::size_t i = 0; i < firstVolume.size(); ++i) placements.push_back({firstVolume[i].position, i});
        const DicomHeader& h1 = w.headers[firstVolume.front().file];
        try {
            if (placements.size() > 1) {
                info.spacing[2] = orderSlices(placements, h1.rowDirection.cross(h1.columnDirection).normalized(),
                    positionTolerance, std::min(directionTol, kMaxDriftPerMm))
                                      .step;
            }
        } catch (const ValueError&) {
        }
        return;
    }

    Plan plan;
    plan.volume = volume;
    plan.slices = volumeSlices(w.headers, set, volume);
    // Every slice of the volume must share its first one's grid: orientation,
    // size, pixel spacing (other volumes of the series, a localizer say, may not).
    const DicomHeader& lead = w.headers[plan.slices.front().file];
    try {
        std::set<std::size_t> files;
        for (const Slice& s : plan.slices) files.insert(s.file);
        for (std::size_t f : files) checkSameGrid(lead, w.headers[f]);
    } catch (const IoError& e) {
        if (info.problem.empty()) info.problem = e.what();
        return;
    }
    plan.row = lead.rowDirection;
    plan.col = lead.columnDirection;
    plan.normal = lead.rowDirection.cross(lead.columnDirection).normalized();
    if (volume > 0) info.orientation = orientationName(plan.normal);
    std::vector<SlicePlacement> placements;
    for (std::size_t i = 0; i < plan.slices.size(); ++i) placements.push_back({plan.slices[i].position, i});
    try {
        plan.stack = orderSlices(placements, plan.normal, positionTolerance, std::min(directionTol, kMaxDriftPerMm));
    } catch (const ValueError& e) {
        if (info.problem.empty()) info.problem = folder.string() + ": (0020,0032) ImagePositionPatient: " + e.what();
        return;
    }
    if (plan.slices.size() > 1)
        info.spacing[2] = plan.stack.step;
    else if (lead.sliceThickness > 0)
        info.spacing[2] = lead.sliceThickness;
    if (!plan.stack.problem.empty()) {
        if (lead.gantryTilt != 0.0 && plan.stack.tilted) {
            plan.stack.problem += " ((0018,1120) GantryDetectorTilt " + std::to_string(lead.gantryTilt) + " deg)";
        }
        if (o.irregular == IrregularSlices::Refuse && info.problem.empty()) {
            info.problem = folder.string() + ": (0020,0032) ImagePositionPatient: " + plan.stack.problem +
                "; refusing (--resample loads it on a uniform grid)";
        }
    }
    w.plan = std::move(plan);
}

/// Series @p wanted of the table: its UID, SeriesNumber, "#index", or a plain
/// number naming one series as index or SeriesNumber.
const DicomSeriesInfo& findSeries(const std::vector<DicomSeriesInfo>& all, const std::string& wanted)
{
    const auto describe = [](const DicomSeriesInfo& s) {
        return "#" + std::to_string(s.index) + " (SeriesNumber " + (s.number.empty() ? "none" : s.number) + ", " +
            s.modality + (s.description.empty() ? "" : " \"" + s.description + "\"") + ", " + s.uid + ")";
    };
    for (const auto& s : all) {
        if (s.uid == wanted) return s;
    }
    const bool hash = !wanted.empty() && wanted.front() == '#';
    const std::string digits = hash ? wanted.substr(1) : wanted;
    const bool numeric = !digits.empty() && digits.size() < 9 &&
        std::all_of(digits.begin(), digits.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
    std::vector<const DicomSeriesInfo*> found;
    if (numeric) {
        const long n = std::stol(digits);
        for (const auto& s : all) {
            const bool byIndex = s.index == n;
            const bool byNumber = !hash && !s.number.empty() && s.number == std::to_string(n);
            if (byIndex || byNumber) found.push_back(&s);
        }
    }
    if (found.size() == 1) return *found.front();
    if (found.size() > 1) {
        std::string list;
        for (const auto* s : found) list += (list.empty() ? "" : "; ") + describe(*s);
        throw ValueError(
            "series '" + wanted + "' is ambiguous: " + list + " (give the UID, or #N for the table's index N)");
    }
    throw ValueError("series '" + wanted + "': not found (" + std::to_string(all.size()) +
        " series present; give a SeriesInstanceUID, a SeriesNumber or #1 to #" + std::to_string(all.size()) +
        " as `voxhap info` lists them)");
}

/// Frames of a file decoded on demand; multi-frame files and mosaics are decoded once.
class FrameSource {
public:
    explicit FrameSource(const std::vector<DicomHeader>& headers) : mHeaders(headers), mCache(headers.size()) { }

    /// The stored samples of @p s's file: decoded into @p scratch (its buffers
    /// reused slice after slice), or a multi-frame file's or mosaic's cached decode.
    const DicomFrames& frames(const Slice& s, DicomFrames& scratch)
    {
        const DicomFrames* frames = &scratch;
        const DicomHeader& h = mHeaders[s.file];
        try {
            if (h.storedFrames > 1 || h.mosaicImages > 0) {
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
            if (frames->rows != h.storedRows || frames->columns != h.storedColumns ||
                frames->frames != h.storedFrames) {
                throw IoError(h.file.string() +
                    ": (0028,0010) Rows / (0028,0011) Columns / (0028,0008) NumberOfFrames: "
                    "pixel data dimensions differ from the header");
            }
        } catch (const IoError&) {
            std::lock_guard<std::mutex> lock(mMutex);
            if (!mFailed) mFailed = s.file;
            throw;
        }
        return *frames;
    }

    /// Copy one slice, rescaled, into @p out (rows × columns floats); padding becomes @p air.
    void read(const Slice& s, float* out, float air)
    {
        thread_local DicomFrames scratch; // one per decoding thread
        const DicomFrames& f = frames(s, scratch);
        const DicomHeader& h = mHeaders[s.file];
        for (int y = 0; y < h.rows; ++y) {
            samplesToFloat(f, s.frame, std::size_t(s.row0 + y) * std::size_t(f.columns) + std::size_t(s.col0),
                std::size_t(h.columns), s.slope, s.intercept, h.padding, air,
                out + std::size_t(y) * std::size_t(h.columns));
        }
    }

    const DicomHeader& header(const Slice& s) const { return mHeaders[s.file]; }
    /// Note that file @p file could not be read (the first such file is failed()).
    void fail(std::size_t file)
    {
        std::lock_guard<std::mutex> lock(mMutex);
        if (!mFailed) mFailed = file;
    }
    /// The file whose decode failed first, if any.
    std::optional<std::size_t> failed() const { return mFailed; }

private:
    const std::vector<DicomHeader>& mHeaders;
    std::vector<std::shared_ptr<const DicomFrames>> mCache;
    DicomDecodeProcess mDecoder; // GDCM's decodes, for files not read directly
    std::mutex mMutex;
    std::optional<std::size_t> mFailed;
};

/// The pixel data of one uncompressed file, read a few rows at a time with
/// pread (safe from any thread; a file that shrinks under the load gives a
/// short read and an error, where a memory map would give SIGBUS).
struct PixelFile {
    PixelFile(const DicomHeader& h, const DicomFrames& l, std::size_t i) : header(h), layout(l), index(i) { }
    PixelFile(PixelFile&& o) noexcept : header(o.header), layout(o.layout), index(o.index), fd(o.fd) { o.fd = -1; }
    PixelFile(const PixelFile&) = delete;
    PixelFile& operator=(const PixelFile&) = delete;
    PixelFile& operator=(PixelFile&&) = delete;
    ~PixelFile()
    {
        if (fd >= 0) ::close(fd);
    }
    bool open()
    {
        fd = ::open(header.file.c_str(), O_RDONLY | O_CLOEXEC);
        return fd >= 0;
    }
    /// Rows y0 .. y1 - 1 of the (only) frame into @p out.
    /// @throw IoError naming the file and PixelData when they cannot be read
    void readRows(int y0, int y1, std::vector<char>& out) const
    {
        const std::size_t rowBytes = std::size_t(layout.columns) * sampleBytes(layout.type);
        const std::size_t want = rowBytes * std::size_t(y1 - y0);
        out.resize(want);
        std::uint64_t at = header.pixelOffset + std::uint64_t(y0) * rowBytes;
        for (std::size_t got = 0; got < want;) {
            const ssize_t n = ::pread(fd, out.data() + got, want - got, off_t(at));
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) {
                const std::uint64_t expected = std::uint64_t(rowBytes) * std::uint64_t(layout.rows);
                throw IoError(header.file.string() + ": (7FE0,0010) PixelData: cannot read " +
                    std::to_string(expected) + " bytes");
            }
            got += std::size_t(n);
            at += std::uint64_t(n);
        }
    }
    const DicomHeader& header;
    const DicomFrames& layout;
    std::size_t index; ///< into the series' headers
    int fd = -1;
};

/// Slab k0 .. k0 + n - 1 holds integer samples (at most 32 bits) under a
/// rescale below 1e28: far inside float's range (2^32 · 1e28 < 3.4e38), so
/// there is no NaN or inf to look for.
bool integerSamples(
    const Plan& plan, const std::vector<SlicePlacement>& order, const std::vector<DicomFrames>& layouts, int k0, int n)
{
    constexpr double kFiniteRescale = 1e28;
    bool finite = true;
    for (int k = 0; k < n; ++k) {
        const Slice& s = plan.slices[order[std::size_t(k0 + k)].source];
        const SampleType type = layouts[s.file].type;
        finite = finite && type != SampleType::Float32 && type != SampleType::Float64 &&
            std::abs(s.slope) < kFiniteRescale && std::abs(s.intercept) < kFiniteRescale;
    }
    return finite;
}

/// The resampled grid: in-plane index range that holds every source voxel of
/// every slice (a tilted stack's slices shift in plane), planes along the normal.
struct ResampleGrid {
    int i0 = 0, j0 = 0, nx = 0, ny = 0, nz = 0;
    std::int64_t outside = 0; ///< source voxel centres outside the grid (0 by construction; counted, not assumed)
};

ResampleGrid coveringGrid(const Plan& plan, int nx, int ny, double dx, double dy)
{
    const SliceStackGeometry& stack = plan.stack;
    const Vec3d p0 = stack.slices.front().position;
    double uMin = 0, uMax = 0, vMin = 0, vMax = 0;
    std::vector<std::pair<double, double>> offsets;
    for (const auto& s : stack.slices) {
        const Vec3d rel = s.position - p0;
        const double u = rel.dot(plan.row) / dx, v = rel.dot(plan.col) / dy;
        offsets.emplace_back(u, v);
        uMin = std::min(uMin, u), uMax = std::max(uMax, u), vMin = std::min(vMin, v), vMax = std::max(vMax, v);
    }
    ResampleGrid g;
    // Grid voxel i covers [i − ½, i + ½]: a source centre at u belongs to round(u).
    g.i0 = int(std::floor(uMin + 0.5));
    g.j0 = int(std::floor(vMin + 0.5));
    g.nx = int(std::floor(uMax + 0.5)) + nx - g.i0;
    g.ny = int(std::floor(vMax + 0.5)) + ny - g.j0;
    const double length = (stack.slices.back().position - p0).dot(plan.normal);
    // ceil, not round: the last slice must fall inside the last plane's half step.
    g.nz = int(std::ceil(length / stack.step - 0.5)) + 1;
    // Count the source centres outside [i0 − ½, i0 + nx − ½] × [j0 − ½, ...] × [−½ step, (nz − ½) step].
    for (std::size_t k = 0; k < stack.slices.size(); ++k) {
        const auto [u, v] = offsets[k];
        const double along = (stack.slices[k].position - p0).dot(plan.normal) / stack.step;
        if (along < -0.5 || along > g.nz - 0.5) {
            g.outside += std::int64_t(nx) * ny;
            continue;
        }
        std::int64_t inU = 0, inV = 0;
        for (int i = 0; i < nx; ++i) inU += (u + i >= g.i0 - 0.5 && u + i <= g.i0 + g.nx - 0.5) ? 1 : 0;
        for (int j = 0; j < ny; ++j) inV += (v + j >= g.j0 - 0.5 && v + j <= g.j0 + g.ny - 0.5) ? 1 : 0;
        g.outside += std::int64_t(nx) * ny - inU * inV;
    }
    return g;
}

/// Raised inside a load when a file of the series cannot be decoded: under
/// skipBad the load starts again without it.
struct BadFile {
    std::size_t file;
    std::string message;
};

} // namespace

bool looksLikeDicom(const fs::path& path)
{
    std::error_code ec;
    if (fs::is_directory(path, ec)) return true;
    std::ifstream in(path, std::ios::binary);
    char magic[132] = {};
    if (!in.read(magic, 2)) return false;
    if (static_cast<unsigned char>(magic[0]) == 0x1f && static_cast<unsigned char>(magic[1]) == 0x8b) {
        // gzip: a .dcm.gz is DICOM; a .nii.gz is not, and its name says so.
        const std::string name = path.filename().string();
        return name.size() > 3 && name.compare(name.size() - 3, 3, ".gz") == 0 &&
            name.find(".nii") == std::string::npos;
    }
    if (!in.read(magic + 2, sizeof magic - 2)) return false;
    return std::string(magic + 128, 4) == "DICM";
}

namespace {

/// The catalog, and the per-series work behind it, for one set of options.
struct Study {
    DicomCatalog catalog;
    std::vector<SeriesWork> work;
};

Study study(const std::vector<fs::path>& inputs, const DicomOptions& o)
{
    Study st;
    st.catalog.scan = scanDicomInputs(inputs, o.memoryCapBytes);
    DicomScan& scan = st.catalog.scan;
    st.catalog.skipped = scan.skipped;
    std::map<std::string, std::vector<DicomHeader>> byUid;
    for (DicomHeader& h : scan.images) byUid[h.seriesUid].push_back(std::move(h));
    scan.images.clear();
    // Table order: SeriesNumber (numerically; none last), then UID.
    std::vector<std::pair<std::string, std::vector<DicomHeader>>> ordered(
        std::make_move_iterator(byUid.begin()), std::make_move_iterator(byUid.end()));
    const auto numberOf = [](const std::vector<DicomHeader>& hs) {
        char* end = nullptr;
        const std::string& n = hs.front().seriesNumber;
        const double v = std::strtod(n.c_str(), &end);
        return n.empty() || end != n.c_str() + n.size() ? 1e300 : v;
    };
    std::stable_sort(ordered.begin(), ordered.end(),
        [&](const auto& a, const auto& b) { return numberOf(a.second) < numberOf(b.second); });
    for (auto& [uid, headers] : ordered) {
        SeriesWork w;
        w.info.index = int(st.work.size()) + 1;
        w.info.uid = uid;
        w.info.modality = headers.front().modality;
        w.info.description = headers.front().seriesDescription;
        w.info.number = headers.front().seriesNumber;
        for (const auto& h : headers) w.info.files.push_back(h.file);
        w.info.rows = headers.front().rows;
        w.info.columns = headers.front().columns;
        for (const auto& h : headers) w.info.slices += h.frames;
        st.work.push_back(std::move(w));
        studySeries(st.work.back(), std::move(headers), scan.skipped, o, scan.inflatedFrom);
    }
    for (auto& w : st.work) {
        w.info.problem = scan.originalNames(w.info.problem);
        for (auto& f : w.info.files) {
            if (auto it = scan.inflatedFrom.find(f.string()); it != scan.inflatedFrom.end()) f = it->second;
        }
        st.catalog.series.push_back(w.info);
        st.catalog.headers.push_back(w.headers);
    }
    return st;
}

/// The inputs as one line, for the messages that name them all.
std::string inputsLine(const std::vector<fs::path>& inputs)
{
    std::string what;
    for (const auto& in : inputs) what += (what.empty() ? "" : ", ") + in.string();
    return what;
}

std::string skippedSummary(const std::vector<DicomSkippedFile>& skipped)
{
    std::map<std::string, int> counts;
    for (const auto& s : skipped) ++counts[s.category];
    std::string out;
    for (const auto& [category, n] : counts) out += (out.empty() ? "" : ", ") + std::to_string(n) + " " + category;
    return out;
}

int rank(const DicomSeriesInfo& s)
{
    if (s.modality == "CT") return 0;
    if (s.weighting == "T1 map" || s.weighting == "T1-weighted") return 1;
    return 2;
}

} // namespace

const DicomSeriesInfo* chooseDefaultSeries(const DicomCatalog& catalog)
{
    const DicomSeriesInfo* best = nullptr;
    for (const auto& s : catalog.series) {
        if (!s.problem.empty()) continue;
        if (!best || rank(s) < rank(*best) || (rank(s) == rank(*best) && s.voxels > best->voxels)) best = &s;
    }
    return best;
}

DicomCatalog catalogDicom(const std::vector<fs::path>& inputs, const DicomOptions& options)
{
    return study(inputs, options).catalog;
}

std::vector<DicomSeriesInfo> listDicomSeries(const std::vector<fs::path>& inputs)
{
    DicomCatalog c = catalogDicom(inputs);
    if (c.series.empty()) {
        throw IoError(inputsLine(inputs) + ": no DICOM image found" +
            (c.skipped.empty() ? std::string() : " (set aside: " + skippedSummary(c.skipped) + ")"));
    }
    return c.series;
}

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/// The series to load: the one DicomOptions::series names, else the default rule's.
/// @param because set to why this one
/// @throw IoError when there is none to load, or the named one does not load
const DicomSeriesInfo& chooseSeries(
    const DicomCatalog& catalog, const std::string& what, const DicomOptions& options, std::string& because)
{
    if (catalog.series.empty()) {
        // One damaged file given alone: its own refusal says the most.
        if (catalog.skipped.size() == 1 && catalog.skipped.front().category == "damaged") {
            throw IoError(catalog.skipped.front().reason);
        }
        throw IoError(what + ": no DICOM image found" +
            (catalog.skipped.empty() ? std::string() : " (set aside: " + skippedSummary(catalog.skipped) + ")"));
    }
    if (!options.series.empty()) {
        const DicomSeriesInfo& chosen = findSeries(catalog.series, options.series);
        // Not an option's name: `info` takes --series, `fuse` --ct-series and --mr-series.
        because = "the series asked for (" + options.series + ")";
        if (!chosen.problem.empty()) throw IoError(chosen.problem);
        return chosen;
    }
    const DicomSeriesInfo* chosen = chooseDefaultSeries(catalog);
    if (!chosen) {
        if (catalog.series.size() == 1) throw IoError(catalog.series.front().problem);
        std::string list;
        for (const auto& s : catalog.series) {
            list += (list.empty() ? "" : " | ") + std::string("#") + std::to_string(s.index) + " " + s.modality + ": " +
                s.problem;
        }
        throw IoError(what + ": no series loads as one 3D volume: " + list);
    }
    because = "the default: the largest series that loads as one 3D volume, CT first, then T1 maps and "
              "T1-weighted MR, then other MR";
    return *chosen;
}

/// One loadDicom call: what its steps read, and the files left out so far.
struct DicomLoad {
    const DicomCatalog& catalog;
    const DicomSeriesInfo& chosen;
    const DicomOptions& options;
    std::string because;
    Clock::time_point start;
    double scanSeconds = 0;
    std::vector<DicomSkippedFile> skippedBad;
};

/// The grid a plan loads onto: the slices' own, or the grid covering an
/// irregular stack that is resampled.
struct PlannedGrid {
    Geometry geo;
    ResampleGrid rg;
    bool resample = false;
    int nx = 0, ny = 0; ///< the stored slices' columns and rows
};

PlannedGrid plannedGrid(const Plan& plan, const DicomHeader& first)
{
    PlannedGrid g;
    g.resample = !plan.stack.problem.empty();
    g.nx = first.columns, g.ny = first.rows;
    Geometry& geo = g.geo;
    geo.spacing = Vec3d(first.pixelSpacing[1], first.pixelSpacing[0], 1.0);
    if (plan.slices.size() > 1)
        geo.spacing[2] = plan.stack.step;
    else if (first.sliceThickness > 0)
        geo.spacing[2] = first.sliceThickness; // one slice: nothing else to go by
    else if (first.spacingBetweenSlices)
        geo.spacing[2] = *first.spacingBetweenSlices;
    geo.direction.col(0) = plan.row;
    geo.direction.col(1) = plan.col;
    geo.direction.col(2) = plan.normal;
    geo.origin = plan.stack.slices.front().position;

    g.rg.nx = g.nx, g.rg.ny = g.ny, g.rg.nz = int(plan.slices.size());
    if (g.resample) {
        g.rg = coveringGrid(plan, g.nx, g.ny, geo.spacing[0], geo.spacing[1]);
        geo.origin += double(g.rg.i0) * geo.spacing[0] * plan.row + double(g.rg.j0) * geo.spacing[1] * plan.col;
    }
    return g;
}

/// @throw IoError when loading @p g may need more than the memory cap
void checkMemoryCap(const Plan& plan, const DicomHeader& first, const PlannedGrid& g, std::uint64_t capBytes)
{
    const ResampleGrid& rg = g.rg;
    const std::size_t inPlane = std::size_t(g.nx) * std::size_t(g.ny);
    const std::size_t outPlane = std::size_t(rg.nx) * std::size_t(rg.ny);
    // Worst case: every voxel active in the float grid (leaf overhead is ~1%),
    // plus one slab, plus the whole input stack when resampling.
    const std::uint64_t need = std::uint64_t(outPlane) * std::uint64_t(rg.nz) * sizeof(float) +
        std::uint64_t(outPlane) * SparseSlabs::kSlabSlices * sizeof(float) +
        (g.resample ? std::uint64_t(inPlane) * plan.slices.size() * sizeof(float) : 0);
    if (need > capBytes) {
        throw IoError(first.file.parent_path().string() + ": (0028,0010) Rows × (0028,0011) Columns × slices = " +
            std::to_string(rg.nx) + "×" + std::to_string(rg.ny) + "×" + std::to_string(rg.nz) + " voxels may need " +
            mib(need) + ", over the memory cap of " + mib(capBytes));
    }
}

/// What the three ways of filling the sparse grid share.
struct GridFill {
    const Plan& plan;
    const std::vector<DicomHeader>& headers;
    const PlannedGrid& grid;
    const DicomOptions& options;
    float background;
    FrameSource& source;
    SparseSlabs& sparse;
    double decodeSeconds = 0, sparseSeconds = 0;

    const Slice& slice(int k) const { return plan.slices[plan.stack.slices[std::size_t(k)].source]; }
    void progress(int done) const
    {
        if (options.progress) options.progress(double(done) / grid.rg.nz, {});
    }
};

/// Can every slice be read straight from its file (single frame, uncompressed
/// little-endian, the plan's size)? Fills @p layouts for those files.
bool directLayouts(GridFill& fill, std::vector<DicomFrames>& layouts)
{
    bool direct = true;
    for (std::size_t n = 0; direct && n < fill.plan.slices.size(); ++n) {
        const Slice& s = fill.plan.slices[n];
        const DicomHeader& h = fill.headers[s.file];
        try {
            direct = h.storedFrames == 1 && h.mosaicImages == 0 && h.storedColumns == fill.grid.nx &&
                h.storedRows == fill.grid.ny && nativeFrameLayout(h, layouts[s.file]);
        } catch (const IoError&) {
            fill.source.fail(s.file);
            throw;
        }
    }
    return direct;
}

/// Single-frame uncompressed little-endian files (the shared CT, most
/// exports) are read a row of leaves at a time: each task reads the 8
/// image rows of each slice it converts straight from the files and
/// converts them while they are in its cache, so reading overlaps
/// conversion on every core and the slab's samples never exist whole.
void readDirect(GridFill& fill, const std::vector<DicomFrames>& layouts)
{
    const int nx = fill.grid.nx, ny = fill.grid.ny, nz = fill.grid.rg.nz;
    // Eight slabs (64 slices, as many files open) per parallel loop:
    // few joins of the two cores, a bounded number of open files,
    // and progress reported between batches.
    constexpr int kBatch = 8 * SparseSlabs::kSlabSlices;
    for (int k0 = 0; k0 < nz; k0 += kBatch) {
        const int n = std::min(kBatch, nz - k0);
        const auto t = Clock::now();
        std::vector<PixelFile> files;
        files.reserve(std::size_t(n));
        for (int k = 0; k < n; ++k) {
            const Slice& s = fill.slice(k0 + k);
            files.emplace_back(fill.headers[s.file], layouts[s.file], s.file);
            if (!files.back().open()) {
                fill.source.fail(s.file);
                throw IoError(fill.headers[s.file].file.string() + ": cannot open");
            }
        }
        fill.sparse.addSlabBlocks(
            [&](int z, int y0, int y1, float* out) {
                const Slice& s = fill.slice(k0 + z);
                PixelFile& f = files[std::size_t(z)];
                thread_local std::vector<char> raw; // one per converting thread, reused
                try {
                    f.readRows(y0, y1, raw);
                } catch (const IoError&) {
                    fill.source.fail(f.index);
                    throw;
                }
                const std::size_t rowBytes = std::size_t(nx) * sampleBytes(f.layout.type);
                for (int y = y0; y < y1; ++y) {
                    rawSamplesToFloat(f.layout, raw.data() + std::size_t(y - y0) * rowBytes, std::size_t(nx), s.slope,
                        s.intercept, f.header.padding, fill.background, out + std::size_t(y - y0) * std::size_t(nx));
                }
            },
            nx, ny, k0, n, integerSamples(fill.plan, fill.plan.stack.slices, layouts, k0, n));
        fill.sparseSeconds += secondsSince(t);
        fill.progress(k0 + n);
    }
}

/// The slab's stored samples are decoded, then converted to floats row by
/// row straight into the grid's leaves: the slab never exists as floats.
void decodeSlabs(GridFill& fill)
{
    const int nx = fill.grid.nx, ny = fill.grid.ny, nz = fill.grid.rg.nz;
    std::vector<DicomFrames> decoded(SparseSlabs::kSlabSlices);
    std::vector<const DicomFrames*> frames(SparseSlabs::kSlabSlices, nullptr);
    for (int k0 = 0; k0 < nz; k0 += SparseSlabs::kSlabSlices) {
        const int n = std::min(SparseSlabs::kSlabSlices, nz - k0);
        auto t = Clock::now();
        tbb::parallel_for(0, n,
            [&](int k) { frames[std::size_t(k)] = &fill.source.frames(fill.slice(k0 + k), decoded[std::size_t(k)]); });
        fill.decodeSeconds += secondsSince(t);
        t = Clock::now();
        // Integer samples (at most 32 bits) under a rescale below 1e28 stay
        // far inside float's range (2^32 · 1e28 < 3.4e38): no NaN or inf to look for.
        constexpr double kFiniteRescale = 1e28;
        bool finite = true;
        for (int k = 0; k < n; ++k) {
            const Slice& s = fill.slice(k0 + k);
            const SampleType type = frames[std::size_t(k)]->type;
            finite = finite && type != SampleType::Float32 && type != SampleType::Float64 &&
                std::abs(s.slope) < kFiniteRescale && std::abs(s.intercept) < kFiniteRescale;
        }
        fill.sparse.addSlabRows(
            [&](int z, int y, float* scratch) {
                const Slice& s = fill.slice(k0 + z);
                const DicomFrames& f = *frames[std::size_t(z)];
                samplesToFloat(f, s.frame, std::size_t(s.row0 + y) * std::size_t(f.columns) + std::size_t(s.col0),
                    std::size_t(nx), s.slope, s.intercept, fill.source.header(s).padding, fill.background, scratch);
                return static_cast<const float*>(scratch);
            },
            nx, ny, k0, n, finite);
        fill.sparseSeconds += secondsSince(t);
        fill.progress(k0 + n);
    }
}

/// An irregular stack: every slice read whole, then each plane of the
/// uniform grid interpolated from them (SliceResample.h).
void resampleSlabs(GridFill& fill)
{
    const Geometry& geo = fill.grid.geo;
    const Plan& plan = fill.plan;
    const ResampleGrid& rg = fill.grid.rg;
    const std::size_t inPlane = std::size_t(fill.grid.nx) * std::size_t(fill.grid.ny);
    const std::size_t outPlane = std::size_t(rg.nx) * std::size_t(rg.ny);
    std::vector<float> slab(outPlane * SparseSlabs::kSlabSlices);
    std::vector<float> input(inPlane * plan.slices.size());
    tbb::parallel_for(std::size_t(0), plan.slices.size(),
        [&](std::size_t k) { fill.source.read(fill.slice(int(k)), input.data() + inPlane * k, fill.background); });
    SliceResampler resampler(plan.stack, input.data(), fill.grid.nx, fill.grid.ny, plan.row, plan.col,
        geo.spacing.head<2>(), fill.background);
    for (int k0 = 0; k0 < rg.nz; k0 += SparseSlabs::kSlabSlices) {
        const int n = std::min(SparseSlabs::kSlabSlices, rg.nz - k0);
        tbb::parallel_for(0, n, [&](int k) {
            resampler.sample(geo.origin + double(k0 + k) * geo.spacing[2] * plan.normal, rg.nx, rg.ny,
                slab.data() + outPlane * std::size_t(k));
        });
        fill.sparse.addSlab(slab.data(), rg.nx, rg.ny, k0, n);
        fill.progress(k0 + n);
    }
}

/// Fill @p fill's sparse grid by the fastest way the files allow.
/// @throw BadFile when a file of the series cannot be read
void fillGrid(GridFill& fill)
{
    try {
        std::vector<DicomFrames> layouts(fill.headers.size());
        if (!fill.grid.resample && directLayouts(fill, layouts)) {
            readDirect(fill, layouts);
        } else if (!fill.grid.resample) {
            decodeSlabs(fill);
        } else {
            resampleSlabs(fill);
        }
    } catch (const IoError& e) {
        if (auto bad = fill.source.failed()) throw BadFile{*bad, e.what()};
        throw;
    }
}

/// The volume's metadata from the series' first file and the plan.
void recordMetadata(VolumeMetadata& md, const DicomLoad& load, const SeriesWork& work, const DicomHeader& first,
    const PlannedGrid& g, float airBelow)
{
    const Plan& plan = *work.plan;
    md.modality = first.modality.empty() ? "unknown" : first.modality;
    md.modalitySource = first.modality.empty() ? FactSource::Unknown : FactSource::Header;
    md.source = "DICOM series " + load.chosen.uid;
    md.description = first.seriesDescription;
    md.seriesUid = load.chosen.uid;
    md.extra["slices"] = std::to_string(plan.slices.size());
    if (plan.volume > 0) {
        md.volumeChoice =
            VolumeChoice{int(plan.volume), int(work.volumes->count()), work.volumes->labels[plan.volume - 1]};
    }
    std::ostringstream air;
    air << airBelow;
    md.extra["air_below"] = air.str();
    if (g.resample) {
        md.extra["resampled"] = plan.stack.problem;
        md.extra["interpolation"] = "bilinear within each slice, linear between slices";
        md.extra["source_voxels_outside_grid"] = std::to_string(g.rg.outside);
    }
    if (!load.skippedBad.empty()) md.extra["skipped_bad_files"] = std::to_string(load.skippedBad.size());
}

/// An MR series' intensities become a material (MrMaterial.h); nothing for CT.
std::optional<MrMaterialReport> assignMaterial(Volume& v, const DicomHeader& first, const DicomOptions& options)
{
    if (first.modality != "MR") return std::nullopt;
    MrMaterialOptions mo;
    mo.t1Map = options.t1Map || first.looksLikeT1Map();
    mo.t1Weighted = options.t1Weighted;
    mo.normaliseT1Weighted = options.normaliseT1Weighted;
    mo.removeBackground = options.removeMrBackground;
    recordFieldStrength(v.metadata(), first.fieldStrength, FactSource::Header, options.assumedField);
    MrWeighting weighting = classifyMrWeighting(sequenceFields(first));
    return assignMrMaterial(v, weighting, mo, first.file.parent_path().string());
}

void fillReport(DicomLoadReport& report, const DicomLoad& load, const SeriesWork& work, const Volume& v,
    const PlannedGrid& g, const GridFill& fill, std::optional<MrMaterialReport> mr)
{
    const Plan& plan = *work.plan;
    report.series = load.chosen;
    report.allSeries = load.catalog.series;
    report.skipped = load.catalog.skipped;
    report.skippedBad = load.skippedBad;
    report.volume = plan.volume;
    report.chosenBecause = load.because;
    report.mr = std::move(mr);
    const auto active = v.has(Channel::Hu) ? v.grid(Channel::Hu)
        : v.has(Channel::T1)               ? v.grid(Channel::T1)
                                           : v.grid(Channel::Intensity);
    report.denseVoxels = v.indexBox().voxelCount();
    report.activeVoxels = std::int64_t(active->activeVoxelCount());
    report.memoryBytes = active->memUsage();
    report.resampled = g.resample;
    report.irregularity = plan.stack.problem;
    report.interpolation = g.resample ? "bilinear within each slice, linear between slices" : "";
    report.sourceVoxelsOutside = g.resample ? g.rg.outside : 0;
    report.paddedFiles = 0;
    for (const auto& h : work.headers) report.paddedFiles += h.trailingPadding > 0 ? 1 : 0;
    report.seconds = secondsSince(load.start);
    report.scanSeconds = load.scanSeconds;
    report.decodeSeconds = fill.decodeSeconds;
    report.sparseSeconds = fill.sparseSeconds;
}

/// Load the volume @p work plans.
/// @throw BadFile when a file of it cannot be read
Volume loadPlanned(const DicomLoad& load, const SeriesWork& work, DicomLoadReport* report)
{
    const Plan& plan = *work.plan;
    const DicomOptions& options = load.options;
    const DicomHeader& first = work.headers[plan.slices.front().file];
    const bool isMr = first.modality == "MR";
    const PlannedGrid g = plannedGrid(plan, first);
    checkMemoryCap(plan, first, g, options.memoryCapBytes);

    // MR goes to the intensity channel first; assignMrMaterial moves it.
    const float background = isMr ? kAirIntensity : kAirHu;
    // MR: zero and below is background (magnitude images hold no tissue there).
    const float airBelow = isMr ? std::nextafter(options.airT1, std::numeric_limits<float>::max()) : options.airHu;
    SparseSlabs sparse(background, airBelow);
    FrameSource source(work.headers);
    GridFill fill{plan, work.headers, g, options, background, source, sparse};
    fillGrid(fill);

    Volume v(g.geo, IndexBox{Vec3i::Zero(), Vec3i(g.rg.nx - 1, g.rg.ny - 1, g.rg.nz - 1)});
    Volume::GridPtr grid;
    try {
        grid = sparse.finish();
    } catch (const ValueError& e) {
        throw IoError(first.file.parent_path().string() + ": " + e.what());
    }
    v.setGrid(isMr ? Channel::Intensity : Channel::Hu, grid);
    recordMetadata(v.metadata(), load, work, first, g, airBelow);
    std::optional<MrMaterialReport> mr = assignMaterial(v, first, options);
    if (report) fillReport(*report, load, work, v, g, fill, std::move(mr));
    return v;
}

/// Under --skip-bad: @p work planned again without the file @p bad names.
/// @throw IoError without --skip-bad, or when what is left does not load
void leaveOut(const BadFile& bad, DicomLoad& load, SeriesWork& work)
{
    const std::string message = load.catalog.scan.originalNames(bad.message);
    if (!load.options.skipBad) throw IoError(message + "; --skip-bad loads the rest of the series");
    // Plan again without the file: the gap checks decide whether what is left loads.
    load.skippedBad.push_back({work.headers[bad.file].file, "damaged", message, load.chosen.uid});
    std::vector<DicomHeader> rest;
    for (std::size_t f = 0; f < work.headers.size(); ++f) {
        if (f != bad.file) rest.push_back(work.headers[f]);
    }
    if (rest.empty()) throw IoError(message);
    SeriesWork again;
    again.info = work.info;
    again.info.problem.clear();
    again.info.damagedFiles = 0;
    // The headers are complete: studySeries completes them again, which is harmless.
    studySeries(again, std::move(rest), {}, load.options);
    if (!again.info.problem.empty())
        throw IoError(load.catalog.scan.originalNames(again.info.problem) + " (after leaving out " +
            work.headers[bad.file].file.string() + ", which could not be read)");
    again.bad = work.bad;
    work = std::move(again);
}

} // namespace

Volume loadDicom(const std::vector<fs::path>& inputs, const DicomOptions& options, DicomLoadReport* report)
{
    const auto start = Clock::now();
    Study st = study(inputs, options);
    std::string because;
    const DicomSeriesInfo& chosen = chooseSeries(st.catalog, inputsLine(inputs), options, because);
    SeriesWork& work = st.work[std::size_t(chosen.index - 1)];
    DicomLoad load{st.catalog, chosen, options, std::move(because), start, secondsSince(start), work.bad};
    // Under skipBad a file that fails to decode is left out and the volume
    // planned again (the gap checks see the missing slice).
    for (;;) {
        try {
            return loadPlanned(load, work, report);
        } catch (const BadFile& bad) {
            leaveOut(bad, load, work);
        }
    }
}

} // namespace voxhap::volume
