// SPDX-License-Identifier: Apache-2.0
/// @file DicomHeaders.cpp
/// @brief Header scanning with gdcm::Scanner; per-frame positions of
/// multi-frame files from their functional groups.

#include "volume/DicomHeaders.h"

#include "volume/DicomPixels.h"
#include "volume/DicomPreflight.h"
#include "volume/Errors.h"

#include <Eigen/Geometry>
#include <gdcmAttribute.h>
#include <gdcmImageHelper.h>
#include <gdcmReader.h>
#include <gdcmScanner.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <set>
#include <sstream>

namespace voxhap::volume {

namespace {

namespace fs = std::filesystem;

const gdcm::Tag kSeriesUid(0x0020, 0x000e), kModality(0x0008, 0x0060), kSeriesDescription(0x0008, 0x103e),
    kSeriesNumber(0x0020, 0x0011), kImageType(0x0008, 0x0008), kRows(0x0028, 0x0010), kColumns(0x0028, 0x0011),
    kFrames(0x0028, 0x0008), kPosition(0x0020, 0x0032), kOrientation(0x0020, 0x0037), kPixelSpacing(0x0028, 0x0030),
    kThickness(0x0018, 0x0050), kSlope(0x0028, 0x1053), kIntercept(0x0028, 0x1052), kTilt(0x0018, 0x1120),
    kPadding(0x0028, 0x0120), kPixelRepresentation(0x0028, 0x0103), kSamplesPerPixel(0x0028, 0x0002),
    kBitsAllocated(0x0028, 0x0100), kBitsStored(0x0028, 0x0101), kHighBit(0x0028, 0x0102),
    kFieldStrength(0x0018, 0x0087);

std::string tagName(const gdcm::Tag& t, const char* name)
{
    char buf[16];
    std::snprintf(buf, sizeof buf, "(%04X,%04X)", t.GetGroup(), t.GetElement());
    return std::string(buf) + " " + name;
}

std::string trim(const char* s)
{
    if (!s) return {};
    std::string v(s);
    const auto notSpace = [](unsigned char c) { return !std::isspace(c) && c != '\0'; };
    v.erase(v.begin(), std::find_if(v.begin(), v.end(), notSpace));
    v.erase(std::find_if(v.rbegin(), v.rend(), notSpace).base(), v.end());
    return v;
}

/// A backslash-separated list of decimal numbers, each finite.
std::vector<double> numbers(const std::string& text, const fs::path& file, const gdcm::Tag& tag, const char* name,
                            std::size_t expected)
{
    std::vector<double> out;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, '\\')) {
        const std::string t = trim(item.c_str());
        char* end = nullptr;
        const double d = std::strtod(t.c_str(), &end);
        if (t.empty() || end != t.c_str() + t.size() || !std::isfinite(d)) {
            throw IoError(file.string() + ": " + tagName(tag, name) + ": '" + text + "' is not a list of numbers");
        }
        out.push_back(d);
    }
    if (expected && out.size() != expected) {
        throw IoError(file.string() + ": " + tagName(tag, name) + ": expected " + std::to_string(expected) +
                      " numbers, got '" + text + "'");
    }
    return out;
}

std::optional<double> optionalNumber(const char* value, const fs::path& file, const gdcm::Tag& tag, const char* name)
{
    const std::string t = trim(value);
    if (t.empty()) return std::nullopt;
    return numbers(t, file, tag, name, 1).front();
}

int positiveInt(const char* value, const fs::path& file, const gdcm::Tag& tag, const char* name)
{
    const auto v = optionalNumber(value, file, tag, name);
    if (!v || *v < 1 || *v > 1e6 || *v != std::floor(*v)) {
        throw IoError(file.string() + ": " + tagName(tag, name) + ": expected a positive whole number, got '" +
                      trim(value) + "'");
    }
    return int(*v);
}

std::vector<fs::path> expand(const std::vector<fs::path>& inputs)
{
    std::vector<fs::path> files;
    for (const auto& in : inputs) {
        std::error_code ec;
        if (fs::is_directory(in, ec)) {
            std::vector<fs::path> found;
            for (const auto& e : fs::recursive_directory_iterator(in, fs::directory_options::skip_permission_denied, ec)) {
                if (e.is_regular_file()) found.push_back(e.path());
            }
            if (ec) throw IoError(in.string() + ": cannot list the directory (" + ec.message() + ")");
            std::sort(found.begin(), found.end());
            files.insert(files.end(), found.begin(), found.end());
        } else if (fs::is_regular_file(in, ec)) {
            files.push_back(in);
        } else {
            throw IoError(in.string() + ": no such file or directory");
        }
    }
    return files;
}

gdcm::Directory::FilenamesType names(const std::vector<fs::path>& files)
{
    gdcm::Directory::FilenamesType out;
    for (const auto& f : files) out.push_back(f.string());
    return out;
}

/// Per-frame ImagePositionPatient of an enhanced multi-frame file
/// (5200,9230) PerFrameFunctionalGroups → (0020,9113) PlanePosition; empty if absent.
std::vector<Vec3d> perFramePositions(const gdcm::DataSet& ds)
{
    std::vector<Vec3d> out;
    const gdcm::Tag perFrame(0x5200, 0x9230), planePosition(0x0020, 0x9113);
    if (!ds.FindDataElement(perFrame)) return out;
    auto sq = ds.GetDataElement(perFrame).GetValueAsSQ();
    if (!sq) return out;
    for (gdcm::SequenceOfItems::SizeType i = 1; i <= sq->GetNumberOfItems(); ++i) { // GDCM items are 1-based
        const gdcm::DataSet& item = sq->GetItem(i).GetNestedDataSet();
        if (!item.FindDataElement(planePosition)) return {};
        auto pp = item.GetDataElement(planePosition).GetValueAsSQ();
        if (!pp || pp->GetNumberOfItems() < 1) return {};
        const gdcm::DataSet& p = pp->GetItem(1).GetNestedDataSet();
        if (!p.FindDataElement(kPosition)) return {};
        gdcm::Attribute<0x0020, 0x0032> ipp;
        ipp.SetFromDataElement(p.GetDataElement(kPosition));
        out.emplace_back(ipp[0], ipp[1], ipp[2]);
    }
    return out;
}

/// Geometry of a multi-frame file: GDCM's helpers read the shared and
/// per-frame functional groups of enhanced objects.
void readMultiFrame(DicomHeader& h)
{
    gdcm::Reader reader;
    reader.SetFileName(h.file.string().c_str());
    // The whole file: elements out of order after the pixel data are part of
    // what ImageHelper reads, and of what DicomElementRules checked.
    if (!reader.Read()) throw IoError(h.file.string() + ": not a readable DICOM file");
    const gdcm::File& file = reader.GetFile();
    const std::vector<double> dir = gdcm::ImageHelper::GetDirectionCosinesValue(file);
    const std::vector<double> origin = gdcm::ImageHelper::GetOriginValue(file);
    const std::vector<double> spacing = gdcm::ImageHelper::GetSpacingValue(file);
    const std::vector<double> rescale = gdcm::ImageHelper::GetRescaleInterceptSlopeValue(file);
    if (dir.size() != 6 || origin.size() < 3 || spacing.size() < 3 || rescale.size() != 2) {
        throw IoError(h.file.string() + ": (5200,9229) SharedFunctionalGroups: no plane geometry for the frames");
    }
    h.rowDirection = Vec3d(dir[0], dir[1], dir[2]);
    h.columnDirection = Vec3d(dir[3], dir[4], dir[5]);
    h.pixelSpacing[0] = spacing[1]; // GDCM orders spacing x (between columns), y (between rows)
    h.pixelSpacing[1] = spacing[0];
    h.intercept = rescale[0];
    h.slope = rescale[1];
    h.framePositions = perFramePositions(file.GetDataSet());
    if (h.framePositions.empty()) { // legacy multi-frame: evenly spaced along the normal
        const Vec3d n = h.rowDirection.cross(h.columnDirection).normalized();
        for (int k = 0; k < h.frames; ++k) h.framePositions.push_back(Vec3d(origin[0], origin[1], origin[2]) + k * spacing[2] * n);
    }
    if (int(h.framePositions.size()) != h.frames) {
        throw IoError(h.file.string() + ": (5200,9230) PerFrameFunctionalGroups: " +
                      std::to_string(h.framePositions.size()) + " plane positions for " + std::to_string(h.frames) +
                      " frames");
    }
}

} // namespace

bool DicomHeader::looksLikeT1Map() const
{
    std::string text = imageType + " " + seriesDescription;
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return char(std::toupper(c)); });
    text.erase(std::remove_if(text.begin(), text.end(), [](char c) { return c == ' ' || c == '_' || c == '-'; }), text.end());
    return text.find("T1MAP") != std::string::npos;
}

namespace {

/// The identity and geometry tags of @p files, one gdcm::Scanner pass; files
/// that are not DICOM images are skipped.
std::vector<DicomHeader> scanChunk(const std::vector<fs::path>& files)
{
    // One scan reads every tag any step needs: headers are parsed once per load.
    gdcm::Scanner scanner;
    for (const auto& t : {kSeriesUid, kModality, kSeriesDescription, kSeriesNumber, kImageType, kRows, kColumns, kFrames,
                          kPosition, kOrientation, kPixelSpacing, kThickness, kSlope, kIntercept, kTilt, kPadding,
                          kPixelRepresentation, kSamplesPerPixel, kBitsAllocated, kBitsStored, kHighBit, kFieldStrength}) {
        scanner.AddTag(t);
    }
    scanner.Scan(names(files));
    std::vector<DicomHeader> out;
    for (const auto& f : files) {
        const std::string name = f.string();
        if (!scanner.IsKey(name.c_str())) continue; // not DICOM
        const char* rows = scanner.GetValue(name.c_str(), kRows);
        if (!rows) continue; // DICOM without an image (DICOMDIR, reports)
        DicomHeader h;
        h.file = f;
        for (const auto& [tag, value] : scanner.GetMapping(name.c_str())) {
            if (value) h.tags[std::uint32_t(tag.GetGroup()) << 16 | tag.GetElement()] = value;
        }
        h.seriesUid = trim(scanner.GetValue(name.c_str(), kSeriesUid));
        h.modality = trim(scanner.GetValue(name.c_str(), kModality));
        h.seriesDescription = trim(scanner.GetValue(name.c_str(), kSeriesDescription));
        h.seriesNumber = trim(scanner.GetValue(name.c_str(), kSeriesNumber));
        h.rows = positiveInt(rows, f, kRows, "Rows");
        h.columns = positiveInt(scanner.GetValue(name.c_str(), kColumns), f, kColumns, "Columns");
        const char* frames = scanner.GetValue(name.c_str(), kFrames);
        h.frames = trim(frames).empty() ? 1 : positiveInt(frames, f, kFrames, "NumberOfFrames");
        out.push_back(std::move(h));
    }
    return out;
}

} // namespace

std::vector<DicomHeader> scanDicomHeaders(const std::vector<fs::path>& inputs)
{
    quietGdcm();
    const std::vector<fs::path> all = expand(inputs);
    // Only files that pass the structural walk reach GDCM (it aborts on truncated
    // ones). Walk and scan run in parallel over chunks of files, each chunk with
    // its own scanner: the header pass is a third of a load when serial.
    std::vector<std::uint8_t> dicom(all.size(), 0);
    std::vector<DicomPixelLocation> where(all.size());
    tbb::parallel_for(std::size_t(0), all.size(), [&](std::size_t n) {
        dicom[n] = preflightDicom(all[n], &where[n]) == DicomKind::Dicom;
    });
    std::map<fs::path, const DicomPixelLocation*> located;
    for (std::size_t n = 0; n < all.size(); ++n) located[all[n]] = &where[n];
    std::vector<fs::path> files;
    for (std::size_t n = 0; n < all.size(); ++n) {
        if (dicom[n]) files.push_back(all[n]);
    }
    constexpr std::size_t kChunk = 16; // files per scanner: enough to amortise its set-up
    const std::size_t chunks = (files.size() + kChunk - 1) / kChunk;
    std::vector<std::vector<DicomHeader>> found(chunks);
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
        const std::vector<fs::path> part(files.begin() + std::ptrdiff_t(c * kChunk),
                                         files.begin() + std::ptrdiff_t(std::min(files.size(), (c + 1) * kChunk)));
        found[c] = scanChunk(part);
    });
    std::vector<DicomHeader> out;
    for (auto& part : found) {
        for (auto& h : part) {
            const DicomPixelLocation& w = *located.at(h.file);
            h.transferSyntax = w.transferSyntax;
            if (w.found) h.pixelOffset = w.offset, h.pixelLength = w.length;
            out.push_back(std::move(h));
        }
    }
    if (out.empty()) {
        std::string what;
        for (const auto& in : inputs) what += (what.empty() ? "" : ", ") + in.string();
        throw IoError(what + ": no DICOM image found");
    }
    return out;
}

std::vector<DicomHeader> readSeriesHeaders(const std::vector<fs::path>& files)
{
    std::vector<DicomHeader> out = scanDicomHeaders(files);
    if (out.size() != files.size()) throw IoError(files.front().parent_path().string() + ": not every file is a DICOM image");
    for (DicomHeader& h : out) completeDicomHeader(h);
    return out;
}

void completeDicomHeader(DicomHeader& h)
{
    const fs::path& f = h.file;
    const std::string name = f.string();
    const auto get = [&](const gdcm::Tag& t) -> const char* {
        const auto it = h.tags.find(std::uint32_t(t.GetGroup()) << 16 | t.GetElement());
        return it == h.tags.end() ? nullptr : it->second.c_str();
    };
    {
        // Debian's GDCM asserts (aborts the process) on some out-of-range pixel
        // module values, e.g. SamplesPerPixel > 4: check them before it decodes.
        const auto small = [&](const gdcm::Tag& t, const char* field, double lo, double hi, double fallback) {
            const double v = optionalNumber(get(t), f, t, field).value_or(fallback);
            if (v < lo || v > hi || v != std::floor(v)) {
                throw IoError(name + ": " + tagName(t, field) + ": " + trim(get(t)) + " is out of range");
            }
            return int(v);
        };
        if (small(kSamplesPerPixel, "SamplesPerPixel", 1, 4, 1) != 1) {
            throw IoError(name + ": " + tagName(kSamplesPerPixel, "SamplesPerPixel") + ": " + trim(get(kSamplesPerPixel)) +
                          ": colour images are not volumes");
        }
        const int allocated = small(kBitsAllocated, "BitsAllocated", 1, 64, 16);
        if (allocated != 8 && allocated != 16 && allocated != 32 && allocated != 64) {
            throw IoError(name + ": " + tagName(kBitsAllocated, "BitsAllocated") + ": " + std::to_string(allocated) + " is not supported");
        }
        const int stored = small(kBitsStored, "BitsStored", 1, allocated, allocated);
        small(kHighBit, "HighBit", stored - 1, allocated - 1, stored - 1);
        h.pixelRepresentation = small(kPixelRepresentation, "PixelRepresentation", 0, 1, 0);
        h.bitsAllocated = allocated;
        h.bitsStored = stored;
        h.imageType = trim(get(kImageType));
        h.gantryTilt = optionalNumber(get(kTilt), f, kTilt, "GantryDetectorTilt").value_or(0.0);
        h.sliceThickness = optionalNumber(get(kThickness), f, kThickness, "SliceThickness").value_or(0.0);
        h.fieldStrength = optionalNumber(get(kFieldStrength), f, kFieldStrength, "MagneticFieldStrength");
        h.padding = optionalNumber(get(kPadding), f, kPadding, "PixelPaddingValue");
        if (h.padding && trim(get(kPixelRepresentation)) == "1" && *h.padding >= 32768) {
            *h.padding -= 65536; // the scanner shows US/SS padding values unsigned
        }
        if (h.frames > 1) {
            readMultiFrame(h);
        } else {
            const std::string ipp = trim(get(kPosition)), iop = trim(get(kOrientation)), ps = trim(get(kPixelSpacing));
            if (ipp.empty()) throw IoError(name + ": " + tagName(kPosition, "ImagePositionPatient") + ": missing");
            if (iop.empty()) throw IoError(name + ": " + tagName(kOrientation, "ImageOrientationPatient") + ": missing");
            if (ps.empty()) throw IoError(name + ": " + tagName(kPixelSpacing, "PixelSpacing") + ": missing");
            const auto p = numbers(ipp, f, kPosition, "ImagePositionPatient", 3);
            const auto o = numbers(iop, f, kOrientation, "ImageOrientationPatient", 6);
            const auto s = numbers(ps, f, kPixelSpacing, "PixelSpacing", 2);
            h.framePositions = {Vec3d(p[0], p[1], p[2])};
            h.rowDirection = Vec3d(o[0], o[1], o[2]);
            h.columnDirection = Vec3d(o[3], o[4], o[5]);
            h.pixelSpacing[0] = s[0];
            h.pixelSpacing[1] = s[1];
            h.slope = optionalNumber(get(kSlope), f, kSlope, "RescaleSlope").value_or(1.0);
            h.intercept = optionalNumber(get(kIntercept), f, kIntercept, "RescaleIntercept").value_or(0.0);
        }
        // Orientation must be two orthonormal directions (writers round to ~6 digits).
        constexpr double kOrthoTolerance = 1e-4;
        const double rn = h.rowDirection.norm(), cn = h.columnDirection.norm();
        if (std::abs(rn - 1) > kOrthoTolerance || std::abs(cn - 1) > kOrthoTolerance ||
            std::abs(h.rowDirection.dot(h.columnDirection)) > kOrthoTolerance) {
            throw IoError(name + ": " + tagName(kOrientation, "ImageOrientationPatient") +
                          ": the row and column directions are not orthonormal");
        }
        h.rowDirection /= rn;
        h.columnDirection /= cn;
        if (!(h.pixelSpacing[0] > 0) || !(h.pixelSpacing[1] > 0)) {
            throw IoError(name + ": " + tagName(kPixelSpacing, "PixelSpacing") + ": must be positive");
        }
        if (h.slope == 0) throw IoError(name + ": " + tagName(kSlope, "RescaleSlope") + ": is zero");
    }
}

void checkSameGrid(const DicomHeader& first, const DicomHeader& h)
{
    // Direction cosines and spacing are decimal strings: 1e-4 (relative) is
    // far above their rounding and far below any real change of orientation.
    constexpr double kSameTolerance = 1e-4;
    const std::string name = h.file.string() + ": ";
    if ((h.rowDirection - first.rowDirection).norm() > kSameTolerance ||
        (h.columnDirection - first.columnDirection).norm() > kSameTolerance) {
        throw IoError(name + tagName(kOrientation, "ImageOrientationPatient") + " differs from " +
                      first.file.filename().string() + "'s: slices of one series must share their orientation");
    }
    if (h.rows != first.rows || h.columns != first.columns) {
        throw IoError(name + tagName(kRows, "Rows") + " / " + tagName(kColumns, "Columns") + " " +
                      std::to_string(h.rows) + "×" + std::to_string(h.columns) + " differ from " +
                      first.file.filename().string() + "'s " + std::to_string(first.rows) + "×" +
                      std::to_string(first.columns));
    }
    for (int i = 0; i < 2; ++i) {
        if (std::abs(h.pixelSpacing[i] - first.pixelSpacing[i]) > kSameTolerance * first.pixelSpacing[i]) {
            throw IoError(name + tagName(kPixelSpacing, "PixelSpacing") + " differs from " +
                          first.file.filename().string() + "'s");
        }
    }
}

} // namespace voxhap::volume
