// SPDX-License-Identifier: Apache-2.0
/// @file DicomHeaders.cpp
/// @brief Header scanning with gdcm::Scanner; per-frame positions of
/// multi-frame files from their functional groups.

#include "volume/dicom/DicomHeaders.h"

#include "core/Errors.h"
#include "volume/dicom/detail/DicomMosaic.h"
#include "volume/dicom/detail/DicomPixels.h"
#include "volume/dicom/detail/DicomPreflight.h"
#include "volume/dicom/detail/StoredPrecision.h"
#include "volume/io/GzipFile.h"

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
#include <cstring>
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
    kFieldStrength(0x0018, 0x0087), kManufacturer(0x0008, 0x0070), kScanningSequence(0x0018, 0x0020),
    kSequenceVariant(0x0018, 0x0021), kSequenceName(0x0018, 0x0024), kProtocolName(0x0018, 0x1030),
    kScanOptions(0x0018, 0x0022), kRepetitionTime(0x0018, 0x0080), kEchoTime(0x0018, 0x0081),
    kInversionTime(0x0018, 0x0082), kFlipAngle(0x0018, 0x1314), kEchoNumbers(0x0018, 0x0086),
    kTemporalPosition(0x0020, 0x0100), kAcquisitionNumber(0x0020, 0x0012), kInstanceNumber(0x0020, 0x0013),
    kTriggerTime(0x0018, 0x1060), kSpacingBetweenSlices(0x0018, 0x0088), kDiffusionBValue(0x0018, 0x9087),
    kPulseSequenceName(0x0018, 0x9005);

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
std::vector<double> numbers(
    const std::string& text, const fs::path& file, const gdcm::Tag& tag, const char* name, std::size_t expected)
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
            for (const auto& e :
                fs::recursive_directory_iterator(in, fs::directory_options::skip_permission_denied, ec)) {
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

/// A number from an element of a nested data set (functional groups),
/// read from its bytes without gdcm::Attribute (which asserts on a VR it
/// does not expect): decimal strings (DS, IS), FD, FL, UL, US, SS, SL.
std::optional<double> itemNumber(const gdcm::DataSet& ds, const gdcm::Tag& t, const char* binaryVr)
{
    if (!ds.FindDataElement(t)) return std::nullopt;
    const gdcm::DataElement& de = ds.GetDataElement(t);
    const gdcm::ByteValue* bv = de.GetByteValue();
    if (!bv || bv->GetLength() == 0) return std::nullopt;
    const char* p = bv->GetPointer();
    const std::uint32_t n = bv->GetLength();
    const std::string vr = binaryVr;
    // Explicit little endian is what enhanced objects are written in; the
    // binary forms are read as such (big endian is retired, PS3.5 Annex A.3).
    if (vr == "FD" && n == 8) {
        double v;
        std::memcpy(&v, p, 8);
        return std::isfinite(v) ? std::optional<double>(v) : std::nullopt;
    }
    if (vr == "FL" && n == 4) {
        float v;
        std::memcpy(&v, p, 4);
        return std::isfinite(v) ? std::optional<double>(v) : std::nullopt;
    }
    if (vr == "UL" && n == 4) {
        std::uint32_t v;
        std::memcpy(&v, p, 4);
        return double(v);
    }
    const std::string text = trim(std::string(p, n).c_str());
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v)) return std::nullopt;
    return v;
}

std::string itemText(const gdcm::DataSet& ds, const gdcm::Tag& t)
{
    if (!ds.FindDataElement(t)) return {};
    const gdcm::ByteValue* bv = ds.GetDataElement(t).GetByteValue();
    return bv ? trim(std::string(bv->GetPointer(), bv->GetLength()).c_str()) : std::string();
}

/// The first item of sequence @p t in @p ds, or nullptr.
const gdcm::DataSet* firstItem(const gdcm::DataSet& ds, const gdcm::Tag& t)
{
    if (!ds.FindDataElement(t)) return nullptr;
    auto sq = ds.GetDataElement(t).GetValueAsSQ();
    if (!sq || sq->GetNumberOfItems() < 1) return nullptr;
    return &sq->GetItem(1).GetNestedDataSet();
}

/// Per-frame rescale and keys of an enhanced multi-frame file, from its
/// per-frame functional groups, each falling back to the shared groups
/// (PS3.3 C.7.6.16): PixelValueTransformation (0028,9145), FrameContent
/// (0020,9111), MREcho (0018,9114), MRDiffusion (0018,9117), and the frame
/// types of MR (0018,9226) and CT (0018,9329).
void readFrameAttributes(const gdcm::DataSet& ds, DicomHeader& h)
{
    const gdcm::Tag perFrame(0x5200, 0x9230), shared(0x5200, 0x9229), pixelValue(0x0028, 0x9145),
        frameContent(0x0020, 0x9111), mrEcho(0x0018, 0x9114), mrDiffusion(0x0018, 0x9117), mrFrameType(0x0018, 0x9226),
        ctFrameType(0x0018, 0x9329);
    const gdcm::DataSet* sharedGroups = firstItem(ds, shared);
    if (!ds.FindDataElement(perFrame)) return;
    auto sq = ds.GetDataElement(perFrame).GetValueAsSQ();
    if (!sq || int(sq->GetNumberOfItems()) != h.frames) return;
    // A macro's item: the frame's own, else the shared one.
    const auto macro = [&](const gdcm::DataSet& frame, const gdcm::Tag& t) -> const gdcm::DataSet* {
        if (const gdcm::DataSet* own = firstItem(frame, t)) return own;
        return sharedGroups ? firstItem(*sharedGroups, t) : nullptr;
    };
    h.frameRescale.clear();
    h.frameKeys.clear();
    for (gdcm::SequenceOfItems::SizeType i = 1; i <= sq->GetNumberOfItems(); ++i) {
        const gdcm::DataSet& frame = sq->GetItem(i).GetNestedDataSet();
        double slope = h.slope, intercept = h.intercept;
        if (const gdcm::DataSet* pv = macro(frame, pixelValue)) {
            slope = itemNumber(*pv, kSlope, "DS").value_or(slope);
            intercept = itemNumber(*pv, kIntercept, "DS").value_or(intercept);
        }
        if (slope == 0)
            throw IoError(h.file.string() + ": (0028,9145) PixelValueTransformation of frame " + std::to_string(i) +
                ": RescaleSlope is zero");
        h.frameRescale.emplace_back(slope, intercept);
        DicomFrameKey k = h.key;
        if (const gdcm::DataSet* fc = macro(frame, frameContent)) {
            if (auto t = itemNumber(*fc, gdcm::Tag(0x0020, 0x9128), "UL")) k.temporalPosition = int(*t);
            if (auto st = itemNumber(*fc, gdcm::Tag(0x0020, 0x9056), "SH")) k.stack = int(*st);
        }
        if (const gdcm::DataSet* e = macro(frame, mrEcho)) {
            if (auto te = itemNumber(*e, gdcm::Tag(0x0018, 0x9082), "FD")) k.echoTime = *te;
        }
        if (const gdcm::DataSet* d = macro(frame, mrDiffusion)) {
            if (auto b = itemNumber(*d, kDiffusionBValue, "FD")) k.bValue = *b;
        }
        const gdcm::DataSet* ft = macro(frame, mrFrameType);
        if (!ft) ft = macro(frame, ctFrameType);
        if (ft) {
            const std::string type = itemText(*ft, gdcm::Tag(0x0008, 0x9007));
            if (!type.empty()) k.imageType = type;
        }
        h.frameKeys.push_back(std::move(k));
    }
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
        for (int k = 0; k < h.frames; ++k)
            h.framePositions.push_back(Vec3d(origin[0], origin[1], origin[2]) + k * spacing[2] * n);
    }
    if (int(h.framePositions.size()) != h.frames) {
        throw IoError(h.file.string() + ": (5200,9230) PerFrameFunctionalGroups: " +
            std::to_string(h.framePositions.size()) + " plane positions for " + std::to_string(h.frames) + " frames");
    }
    readFrameAttributes(file.GetDataSet(), h);
    // Positions and directions come out of GDCM as doubles: their stored
    // digits are not seen here, so the checks use the floors.
    h.positionUnit = h.orientationUnit = h.spacingUnit = 0;
}

} // namespace

bool DicomHeader::looksLikeT1Map() const
{
    std::string text = imageType + " " + seriesDescription;
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return char(std::toupper(c)); });
    text.erase(
        std::remove_if(text.begin(), text.end(), [](char c) { return c == ' ' || c == '_' || c == '-'; }), text.end());
    return text.find("T1MAP") != std::string::npos;
}

std::string DicomHeader::value(std::uint16_t group, std::uint16_t element) const
{
    const auto it = tags.find(std::uint32_t(group) << 16 | element);
    return it == tags.end() ? std::string() : trim(it->second.c_str());
}

std::string DicomFrameKey::separating() const
{
    std::ostringstream os;
    os.precision(6);
    os << imageType << '|';
    if (echoNumber) os << *echoNumber;
    os << '|';
    // Echo times and b-values are decimal strings that writers round
    // differently from slice to slice: 0.01 ms and 1 s/mm² resolve every
    // real difference and none of the rounding.
    if (echoTime) os << std::lround(*echoTime * 100.0);
    os << '|';
    if (temporalPosition) os << *temporalPosition;
    os << '|';
    if (bValue) os << std::lround(*bValue);
    os << '|';
    if (stack) os << *stack;
    return os.str();
}

namespace {

/// The identity and geometry tags of @p files, one gdcm::Scanner pass; files
/// that are not DICOM images go to @p skipped.
std::vector<DicomHeader> scanChunk(const std::vector<fs::path>& files, std::vector<DicomSkippedFile>& skipped)
{
    // One scan reads every tag any step needs: headers are parsed once per load.
    gdcm::Scanner scanner;
    for (const auto& t :
        {kSeriesUid, kModality, kSeriesDescription, kSeriesNumber, kImageType, kRows, kColumns, kFrames, kPosition,
            kOrientation, kPixelSpacing, kThickness, kSlope, kIntercept, kTilt, kPadding, kPixelRepresentation,
            kSamplesPerPixel, kBitsAllocated, kBitsStored, kHighBit, kFieldStrength, kManufacturer, kScanningSequence,
            kSequenceVariant, kSequenceName, kProtocolName, kRepetitionTime, kEchoTime, kInversionTime, kFlipAngle,
            kEchoNumbers, kTemporalPosition, kAcquisitionNumber, kInstanceNumber, kTriggerTime, kSpacingBetweenSlices,
            kDiffusionBValue, kPulseSequenceName, kScanOptions}) {
        scanner.AddTag(t);
    }
    scanner.Scan(names(files));
    std::vector<DicomHeader> out;
    for (const auto& f : files) {
        const std::string name = f.string();
        if (!scanner.IsKey(name.c_str())) {
            skipped.push_back({f, "damaged", name + ": GDCM cannot read the header", {}});
            continue;
        }
        const char* rows = scanner.GetValue(name.c_str(), kRows);
        if (!rows) {
            skipped.push_back(
                {f, "no image", name + ": a CT or MR object without (0028,0010) Rows: no image in it", {}});
            continue;
        }
        DicomHeader h;
        h.file = f;
        for (const auto& [tag, value] : scanner.GetMapping(name.c_str())) {
            if (value) h.tags[std::uint32_t(tag.GetGroup()) << 16 | tag.GetElement()] = value;
        }
        h.seriesUid = trim(scanner.GetValue(name.c_str(), kSeriesUid));
        h.modality = trim(scanner.GetValue(name.c_str(), kModality));
        h.seriesDescription = trim(scanner.GetValue(name.c_str(), kSeriesDescription));
        h.seriesNumber = trim(scanner.GetValue(name.c_str(), kSeriesNumber));
        h.imageType = trim(scanner.GetValue(name.c_str(), kImageType));
        try {
            h.rows = positiveInt(rows, f, kRows, "Rows");
            h.columns = positiveInt(scanner.GetValue(name.c_str(), kColumns), f, kColumns, "Columns");
            const char* frames = scanner.GetValue(name.c_str(), kFrames);
            h.frames = trim(frames).empty() ? 1 : positiveInt(frames, f, kFrames, "NumberOfFrames");
        } catch (const IoError& e) {
            skipped.push_back({f, "damaged", e.what(), h.seriesUid});
            continue;
        }
        h.storedRows = h.rows;
        h.storedColumns = h.columns;
        h.storedFrames = h.frames;
        out.push_back(std::move(h));
    }
    return out;
}

/// An optional value that only orders or separates frames: one that does not
/// parse is left out rather than refusing the file (private tags in
/// implicit-VR files come out of the scanner as raw bytes).
std::optional<double> lenientNumber(const DicomHeader& h, const gdcm::Tag& t)
{
    const std::string v = h.value(t.GetGroup(), t.GetElement());
    if (v.empty()) return std::nullopt;
    std::stringstream in(v);
    std::string first;
    std::getline(in, first, '\\');
    first = trim(first.c_str());
    char* end = nullptr;
    const double d = std::strtod(first.c_str(), &end);
    if (first.empty() || end != first.c_str() + first.size() || !std::isfinite(d)) return std::nullopt;
    return d;
}

/// The element of private tag (@p group, @p element & 0xFF) in the block
/// its creator @p creator reserved (PS3.5 §7.8.1), if the file has that creator.
std::optional<gdcm::Tag> privateElement(
    const DicomHeader& h, std::uint16_t group, const char* creator, std::uint16_t low)
{
    // The creators are elements 0x0010..0x00FF of the group: one range of the map.
    const std::uint32_t first = std::uint32_t(group) << 16 | 0x0010u, last = std::uint32_t(group) << 16 | 0x00FFu;
    for (auto it = h.tags.lower_bound(first); it != h.tags.end() && it->first <= last; ++it) {
        if (trim(it->second.c_str()) == creator) return gdcm::Tag(group, std::uint16_t((it->first & 0xFFu) << 8 | low));
    }
    return std::nullopt;
}

/// The b-value of a classic (single-frame) MR file: the standard element,
/// else the vendors' private ones (as dcm2niix reads them): Siemens
/// (0019,xx0C) B_value, GE (0043,xx39) slop_int_1 (whose first value carries
/// 1e9 on some software versions), Philips (2001,xx03) DiffusionBValue (FL).
std::optional<double> classicBValue(const DicomHeader& h)
{
    if (auto b = lenientNumber(h, kDiffusionBValue)) return b;
    if (auto t = privateElement(h, 0x0019, "SIEMENS MR HEADER", 0x0C)) {
        if (auto b = lenientNumber(h, *t)) return b;
    }
    if (auto t = privateElement(h, 0x0043, "GEMS_PARM_01", 0x39)) {
        if (auto b = lenientNumber(h, *t)) return *b >= 1e9 ? *b - 1e9 : *b;
    }
    if (auto t = privateElement(h, 0x2001, "Philips Imaging DD 001", 0x03)) {
        const std::string raw = h.tags.count(std::uint32_t(t->GetGroup()) << 16 | t->GetElement())
            ? h.tags.at(std::uint32_t(t->GetGroup()) << 16 | t->GetElement())
            : std::string();
        if (raw.size() == 4) { // FL, little endian
            float b;
            std::memcpy(&b, raw.data(), 4);
            if (std::isfinite(b) && b >= 0) return double(b);
        }
    }
    return std::nullopt;
}

} // namespace

DicomScan scanDicomInputs(const std::vector<fs::path>& inputs, std::uint64_t inflateCapBytes)
{
    quietGdcm();
    DicomScan scan;
    std::vector<fs::path> all = expand(inputs);

    // Only files that pass the structural walk reach GDCM (it aborts on truncated
    // ones). Walk and scan run in parallel over chunks of files, each chunk with
    // its own scanner: the header pass is a third of a load when serial.
    std::vector<DicomKind> kind(all.size(), DicomKind::NotDicom);
    std::vector<DicomPixelLocation> where(all.size());
    std::vector<DicomPreflightNotes> notes(all.size());
    std::vector<std::string> damage(all.size());
    const auto walk = [&](std::size_t n) {
        try {
            kind[n] = preflightDicom(all[n], &where[n], &notes[n]);
        } catch (const IoError& e) {
            damage[n] = e.what();
        }
    };
    tbb::parallel_for(std::size_t(0), all.size(), walk);
    // gzip-compressed files (.dcm.gz from some archives) have no DICM preamble:
    // they are inflated, the whole stream verified, into a private folder and
    // walked from there. Only files that are not DICOM are looked at again.
    std::shared_ptr<TemporaryFolder> unpacked;
    std::vector<std::string> gzipDamage(all.size());
    for (std::size_t n = 0; n < all.size(); ++n) {
        if (!damage[n].empty() || kind[n] != DicomKind::NotDicom || !isGzipFile(all[n])) continue;
        if (!unpacked) unpacked = std::make_shared<TemporaryFolder>("voxhap-dicom-gz");
        const fs::path copy = unpacked->path() / (std::to_string(scan.inflatedFrom.size()) + ".dcm");
        try {
            if (!inflateDicomGzip(all[n], copy, inflateCapBytes)) continue; // gzip, but not DICOM inside
        } catch (const IoError& e) {
            gzipDamage[n] = e.what();
            continue;
        }
        scan.inflatedFrom[copy.string()] = all[n].string();
        all[n] = copy;
        walk(n);
    }
    scan.unpacked = unpacked;
    std::map<fs::path, std::size_t> located;
    std::vector<fs::path> files;
    for (std::size_t n = 0; n < all.size(); ++n) {
        if (!gzipDamage[n].empty()) {
            scan.skipped.push_back({all[n], "damaged", gzipDamage[n], {}});
        } else if (!damage[n].empty()) {
            scan.skipped.push_back({all[n], "damaged", damage[n], notes[n].seriesUid});
        } else if (kind[n] == DicomKind::NotDicom) {
            scan.skipped.push_back(
                {all[n], "not DICOM", all[n].string() + ": no DICM preamble: not a DICOM Part 10 file", {}});
        } else if (kind[n] == DicomKind::NonImage) {
            scan.skipped.push_back({all[n], notes[n].nonImageReason,
                all[n].string() + ": " + notes[n].nonImageReason + " (" + notes[n].sopClass + "): not a CT or MR image",
                {}});
        } else {
            located[all[n]] = n;
            files.push_back(all[n]);
        }
    }
    constexpr std::size_t kChunk = 16; // files per scanner: enough to amortise its set-up
    const std::size_t chunks = (files.size() + kChunk - 1) / kChunk;
    std::vector<std::vector<DicomHeader>> found(chunks);
    std::vector<std::vector<DicomSkippedFile>> unread(chunks);
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
        const std::vector<fs::path> part(files.begin() + std::ptrdiff_t(c * kChunk),
            files.begin() + std::ptrdiff_t(std::min(files.size(), (c + 1) * kChunk)));
        found[c] = scanChunk(part, unread[c]);
    });
    for (std::size_t c = 0; c < chunks; ++c) {
        for (auto& h : found[c]) {
            const std::size_t n = located.at(h.file);
            h.transferSyntax = where[n].transferSyntax;
            if (where[n].found) h.pixelOffset = where[n].offset, h.pixelLength = where[n].length;
            h.trailingPadding = notes[n].trailingPadding;
            for (const auto& [tag, value] : notes[n].privateValues) h.tags.emplace(tag, value);
            scan.images.push_back(std::move(h));
        }
        scan.skipped.insert(scan.skipped.end(), unread[c].begin(), unread[c].end());
    }
    std::sort(scan.skipped.begin(), scan.skipped.end(),
        [](const DicomSkippedFile& a, const DicomSkippedFile& b) { return a.file < b.file; });
    for (auto& s : scan.skipped) {
        s.reason = scan.originalNames(s.reason);
        if (auto it = scan.inflatedFrom.find(s.file.string()); it != scan.inflatedFrom.end()) s.file = it->second;
    }
    return scan;
}

std::string DicomScan::originalNames(std::string message) const
{
    for (const auto& [copy, original] : inflatedFrom) {
        for (std::size_t at = message.find(copy); at != std::string::npos;
             at = message.find(copy, at + original.size())) {
            message.replace(at, copy.size(), original);
        }
    }
    return message;
}

std::vector<DicomHeader> scanDicomHeaders(const std::vector<fs::path>& inputs)
{
    DicomScan scan = scanDicomInputs(inputs);
    if (scan.images.empty()) {
        std::string what;
        for (const auto& in : inputs) what += (what.empty() ? "" : ", ") + in.string();
        throw IoError(what + ": no DICOM image found");
    }
    return std::move(scan.images);
}

std::vector<DicomHeader> readSeriesHeaders(const std::vector<fs::path>& files)
{
    std::vector<DicomHeader> out = scanDicomHeaders(files);
    if (out.size() != files.size())
        throw IoError(files.front().parent_path().string() + ": not every file is a DICOM image");
    for (DicomHeader& h : out) completeDicomHeader(h);
    return out;
}

void completeDicomHeader(DicomHeader& h)
{
    if (h.complete) return; // a mosaic's tiles must not be cut twice
    const fs::path& f = h.file;
    const std::string name = f.string();
    const auto get = [&](const gdcm::Tag& t) -> const char* {
        const auto it = h.tags.find(std::uint32_t(t.GetGroup()) << 16 | t.GetElement());
        return it == h.tags.end() ? nullptr : it->second.c_str();
    };
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
        throw IoError(name + ": " + tagName(kBitsAllocated, "BitsAllocated") + ": " + std::to_string(allocated) +
            " is not supported");
    }
    const int stored = small(kBitsStored, "BitsStored", 1, allocated, allocated);
    // HighBit places the stored bits in the word (PS3.5 §8.1.1): bits
    // HighBit − BitsStored + 1 .. HighBit hold the value.
    h.highBit = small(kHighBit, "HighBit", stored - 1, allocated - 1, stored - 1);
    h.pixelRepresentation = small(kPixelRepresentation, "PixelRepresentation", 0, 1, 0);
    h.bitsAllocated = allocated;
    h.bitsStored = stored;
    h.gantryTilt = optionalNumber(get(kTilt), f, kTilt, "GantryDetectorTilt").value_or(0.0);
    h.sliceThickness = optionalNumber(get(kThickness), f, kThickness, "SliceThickness").value_or(0.0);
    h.spacingBetweenSlices = lenientNumber(h, kSpacingBetweenSlices);
    h.fieldStrength = optionalNumber(get(kFieldStrength), f, kFieldStrength, "MagneticFieldStrength");
    h.padding = optionalNumber(get(kPadding), f, kPadding, "PixelPaddingValue");
    if (h.padding && trim(get(kPixelRepresentation)) == "1" && *h.padding >= 32768) {
        *h.padding -= 65536; // the scanner shows US/SS padding values unsigned
    }
    // What separates the volumes of a 4D series (DicomVolumes.h).
    h.key.imageType = h.imageType;
    if (auto v = lenientNumber(h, kEchoNumbers)) h.key.echoNumber = int(*v);
    h.key.echoTime = lenientNumber(h, kEchoTime);
    if (auto v = lenientNumber(h, kTemporalPosition)) h.key.temporalPosition = int(*v);
    if (h.modality == "MR") h.key.bValue = classicBValue(h); // diffusion is MR's alone
    if (auto v = lenientNumber(h, kAcquisitionNumber)) h.key.acquisitionNumber = int(*v);
    if (auto v = lenientNumber(h, kInstanceNumber)) h.key.instanceNumber = int(*v);
    h.key.triggerTime = lenientNumber(h, kTriggerTime);
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
        h.positionUnit = finestUnit(ipp);
        h.orientationUnit = finestUnit(iop);
        h.spacingUnit = finestUnit(ps);
        h.slope = optionalNumber(get(kSlope), f, kSlope, "RescaleSlope").value_or(1.0);
        h.intercept = optionalNumber(get(kIntercept), f, kIntercept, "RescaleIntercept").value_or(0.0);
    }
    // Orientation must be two orthonormal directions, within what the stored digits resolve.
    const double tolerance = directionTolerance(h.orientationUnit);
    const double rn = h.rowDirection.norm(), cn = h.columnDirection.norm();
    if (std::abs(rn - 1) > tolerance || std::abs(cn - 1) > tolerance ||
        std::abs(h.rowDirection.dot(h.columnDirection)) > tolerance) {
        throw IoError(name + ": " + tagName(kOrientation, "ImageOrientationPatient") +
            ": the row and column directions are not orthonormal");
    }
    h.rowDirection /= rn;
    h.columnDirection /= cn;
    if (!(h.pixelSpacing[0] > 0) || !(h.pixelSpacing[1] > 0)) {
        throw IoError(name + ": " + tagName(kPixelSpacing, "PixelSpacing") + ": must be positive");
    }
    if (h.slope == 0) throw IoError(name + ": " + tagName(kSlope, "RescaleSlope") + ": is zero");
    // Siemens mosaics: one stored image holds the slices of a volume as tiles.
    if (isMosaic(h)) readMosaic(h);
    h.complete = true;
}

void checkSameGrid(const DicomHeader& first, const DicomHeader& h)
{
    // Direction cosines and spacing are decimal strings: what their digits
    // cannot resolve is tolerated, and nothing more (StoredPrecision.h).
    const double directions = directionTolerance(std::max(first.orientationUnit, h.orientationUnit));
    const std::string name = h.file.string() + ": ";
    if ((h.rowDirection - first.rowDirection).norm() > directions ||
        (h.columnDirection - first.columnDirection).norm() > directions) {
        throw IoError(name + tagName(kOrientation, "ImageOrientationPatient") + " differs from " +
            first.file.filename().string() + "'s: slices of one series must share their orientation");
    }
    if (h.rows != first.rows || h.columns != first.columns) {
        throw IoError(name + tagName(kRows, "Rows") + " / " + tagName(kColumns, "Columns") + " " +
            std::to_string(h.rows) + "×" + std::to_string(h.columns) + " differ from " +
            first.file.filename().string() + "'s " + std::to_string(first.rows) + "×" + std::to_string(first.columns));
    }
    // Relative 1e-4 at least (the tolerance before the digits were read); a
    // spacing stored to 0.01 mm may differ by one unit between two files.
    const double unit = std::max(first.spacingUnit, h.spacingUnit);
    for (int i = 0; i < 2; ++i) {
        const double tolerance = std::max(kDirectionFloor * first.pixelSpacing[i], unit);
        if (std::abs(h.pixelSpacing[i] - first.pixelSpacing[i]) > tolerance) {
            throw IoError(name + tagName(kPixelSpacing, "PixelSpacing") + " differs from " +
                first.file.filename().string() + "'s");
        }
    }
}

} // namespace voxhap::volume
