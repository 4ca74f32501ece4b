// SPDX-License-Identifier: Apache-2.0
/// @file DicomPreflight.cpp
/// @brief Element-header walk: explicit/implicit VR, little/big endian,
/// undefined-length sequences, items and encapsulated pixel fragments.

#include "volume/dicom/detail/DicomPreflight.h"

#include "core/Errors.h"
#include "volume/dicom/detail/DicomElementRules.h"

#include <gdcmReader.h>
#include <gdcmTransferSyntax.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

namespace voxhap::volume {

namespace {

constexpr std::uint32_t kUndefined = 0xFFFFFFFFu;
constexpr int kMaxDepth = 32;         // real files nest a few levels; bounds the recursion
constexpr std::uint32_t kMaxUid = 65; // longest UID: 64 characters and a padding byte (PS3.5 §9.1)

struct Tag {
    std::uint16_t group = 0, element = 0;
    bool is(std::uint16_t g, std::uint16_t e) const { return group == g && element == e; }
    std::string text() const
    {
        char buf[16];
        std::snprintf(buf, sizeof buf, "(%04X,%04X)", group, element);
        return buf;
    }
};

/// The private elements the loader reads b-values from (DicomHeaders.cpp),
/// and their groups' creator slots: Siemens (0019,xx0C), GE (0043,xx39),
/// Philips (2001,xx03).
bool wantedPrivate(const Tag& t)
{
    if (t.group != 0x0019 && t.group != 0x0043 && t.group != 0x2001) return false;
    if (t.element >= 0x0010 && t.element <= 0x00FF) return true; // a private creator
    const unsigned low = t.element & 0xFFu;
    return (t.group == 0x0019 && low == 0x0C) || (t.group == 0x0043 && low == 0x39) ||
        (t.group == 0x2001 && low == 0x03);
}

/// @p text with bytes outside printable ASCII shown as '?', for messages on one line.
std::string printable(std::string text)
{
    for (char& c : text) {
        if (c < 0x20 || c > 0x7e) c = '?';
    }
    return text;
}

class Walker {
public:
    Walker(const std::filesystem::path& file, std::ifstream& in, std::uint64_t size, DicomPreflightNotes& notes)
        : mFile(file), mIn(in), mSize(size), mNotes(notes)
    {
    }

    /// Meta header (always explicit VR little endian); returns the offset after it.
    std::uint64_t meta(std::uint64_t pos, std::string& transferSyntax)
    {
        std::uint64_t groupEnd = 0;
        for (;;) {
            if (pos >= mSize) break;
            mAt = pos;
            unsigned char h[12]; // 8 bytes, 12 for the long VRs (length() reads the rest)
            read(pos, h, 8, Tag{0x0002, 0x0000});
            const Tag t{u16(h, false), u16(h + 2, false)};
            if (t.group != 0x0002) break;
            // PS3.10 §7.1 uses only these VRs in the meta header; GDCM asserts
            // on others, SQ among them (found by fuzz/FuzzDicomPreflight).
            const std::string vr{char(h[4]), char(h[5])};
            if (vr != "UL" && vr != "OB" && vr != "UI" && vr != "SH" && vr != "AE") {
                fail(t, "value representation '" + printable(vr) + "' is not allowed in the meta header");
            }
            std::uint64_t header = 0;
            const std::uint32_t len = length(pos, h, true, false, t, header);
            if (len == kUndefined) fail(t, "undefined length in the meta header");
            need(pos + header + len, t);
            if (t.is(0x0002, 0x0010)) {
                transferSyntax.resize(len);
                read(pos + header, transferSyntax.data(), len, t);
                // One padding byte, as GDCM drops it; any other is not part of a known UID.
                if (!transferSyntax.empty() && (transferSyntax.back() == '\0' || transferSyntax.back() == ' '))
                    transferSyntax.pop_back();
            }
            if (t.is(0x0002, 0x0002) && len <= kMaxUid) {
                mMetaSopClass.resize(len);
                read(pos + header, mMetaSopClass.data(), len, t);
            }
            if (t.is(0x0002, 0x0000) && len == 4) {
                unsigned char v[4];
                read(pos + header, v, 4, t);
                groupEnd = pos + header + len + u32(v, false);
            }
            pos += header + len;
        }
        // GDCM trusts the group length and the presence of a data set.
        mAt = pos;
        if (groupEnd && groupEnd != pos)
            fail(Tag{0x0002, 0x0000},
                "FileMetaInformationGroupLength does not match the meta header (truncated or corrupt file)");
        if (pos >= mSize) fail(Tag{0x0002, 0x0000}, "no data set after the meta header (truncated file)");
        return pos;
    }

    /// Elements from @p pos to @p end, or to an item delimiter when @p end is undefined.
    std::uint64_t dataset(
        std::uint64_t pos, std::uint64_t end, bool untilDelimiter, bool explicitVr, bool big, int depth)
    {
        if (depth > kMaxDepth) fail(Tag{}, "sequences nested deeper than " + std::to_string(kMaxDepth) + " levels");
        while (untilDelimiter || pos < end) {
            mAt = pos;
            // Zero bytes to the end of the file after a complete top-level
            // element: padding to a block size, which other readers accept.
            // Looked for only where an element header is zero (or cut short),
            // so that a normal file is not read twice.
            const bool top = depth == 0 && !untilDelimiter && pos > mDataSetStart;
            if (top && pos + 8 > end && zerosToEnd(pos)) return padding(pos);
            if (!untilDelimiter && pos + 8 > end) fail(Tag{}, "element header runs past its sequence item");
            unsigned char h[12];
            read(pos, h, 8, Tag{});
            if (top && std::all_of(h, h + 8, [](unsigned char c) { return c == 0; }) && zerosToEnd(pos))
                return padding(pos);
            const Tag t{u16(h, big), u16(h + 2, big)};
            if (t.is(0xFFFE, 0xE00D) && untilDelimiter) return pos + 8; // end of an undefined-length item
            if (depth == 0 && (t.is(0x5200, 0x9229) || t.is(0x5200, 0x9230) || t.is(0x0018, 0x6011)))
                mFunctionalGroups = true;
            // Item tags anywhere else: GDCM would re-read the rest with other
            // lengths than this walk checked (found by fuzz/FuzzDicomPreflight).
            if (t.group == 0xFFFE) fail(t, "item tag outside a sequence");
            std::uint64_t header = 0;
            const std::uint32_t len = length(pos, h, explicitVr, big, t, header);
            pos += header;
            const std::string vr = explicitVr ? std::string{char(h[4]), char(h[5])} : std::string();
            // Pixel data is never a sequence (GDCM asserts on an SQ there).
            if (t.is(0x7FE0, 0x0010) && vr == "SQ") fail(t, "pixel data stored as a sequence");
            if (len == kUndefined) {
                // GDCM asserts unless an undefined length belongs to a sequence,
                // to encapsulated (OB/OW) pixel data or to UN, whose items are
                // implicit VR (CP-246) (fuzz finding).
                bool nestedExplicit = explicitVr;
                if (vr == "UN" && !t.is(0x7FE0, 0x0010))
                    nestedExplicit = false;
                else if (explicitVr && (t.is(0x7FE0, 0x0010) ? vr != "OB" && vr != "OW" : vr != "SQ")) {
                    fail(t, "undefined length with value representation '" + printable(vr) + "'");
                }
                pos = sequence(pos, nestedExplicit, big, depth + 1, t);
            } else {
                need(pos + len, t);
                if (depth == 0 && t.is(0x7FE0, 0x0010)) mPixels = {pos, len};
                if (depth == 0 && t.is(0x0008, 0x0016) && len <= kMaxUid) {
                    mSopClass.resize(len);
                    read(pos, mSopClass.data(), len, t);
                }
                if (depth == 0 && t.is(0x0008, 0x0010)) recognitionCode(pos, len, t);
                if (depth == 0 && len <= 64 && wantedPrivate(t)) {
                    std::string value(len, '\0');
                    read(pos, value.data(), len, t);
                    mNotes.privateValues[std::uint32_t(t.group) << 16 | t.element] = value;
                }
                if (depth == 0 && t.is(0x0020, 0x000E) && len <= kMaxUid) {
                    std::string uid(len, '\0');
                    read(pos, uid.data(), len, t);
                    while (!uid.empty() && (uid.back() == '\0' || uid.back() == ' ')) uid.pop_back();
                    mNotes.seriesUid = uid;
                }
                if (!untilDelimiter) {
                    if (pos + len > end) fail(t, "element runs past its sequence item");
                }
                pos += len;
            }
        }
        return pos;
    }

    /// The SOP class GDCM goes by: the meta header's (0002,0002), else the
    /// data set's (0008,0016); with the tag it came from.
    /// The meta header's (0002,0002) alone (a deflated data set is not walked).
    std::pair<std::string, Tag> metaSopClass() const { return {mMetaSopClass, Tag{0x0002, 0x0002}}; }
    /// Where the top-level PixelData of defined length lies: offset, length.
    const std::optional<std::pair<std::uint64_t, std::uint64_t>>& pixels() const { return mPixels; }
    std::pair<std::string, Tag> sopClass() const
    {
        if (!mMetaSopClass.empty()) return {mMetaSopClass, Tag{0x0002, 0x0002}};
        return {mSopClass, Tag{0x0008, 0x0016}};
    }
    [[noreturn]] void refuse(const Tag& t, const std::string& what) { fail(t, what); }
    /// Where the data set starts (after the meta header): padding needs an element before it.
    void setDataSetStart(std::uint64_t pos) { mDataSetStart = pos; }

    /// True when the data set holds functional groups (or ultrasound regions):
    /// GDCM reads their values on paths that assert (DicomElementRules.h).
    bool functionalGroups() const { return mFunctionalGroups; }

private:
    /// (0008,0010) RecognitionCode (retired, ACR-NEMA): GDCM asserts that a
    /// file holding one is ACR-NEMA (fuzz finding).
    void recognitionCode(std::uint64_t pos, std::uint32_t len, const Tag& t)
    {
        std::string code(std::min<std::uint32_t>(len, 16), '\0');
        read(pos, code.data(), code.size(), t);
        for (const char* ok : {"ACR-NEMA", "ACRNEMA", "MIPS 2.0"}) {
            if (code.rfind(ok, 0) == 0) return;
        }
        fail(t, "RecognitionCode '" + printable(code) + "' is not ACR-NEMA's");
    }

    /// Items of an undefined-length sequence or encapsulated pixel data, up to (FFFE,E0DD).
    std::uint64_t sequence(std::uint64_t pos, bool explicitVr, bool big, int depth, const Tag& owner)
    {
        if (depth > kMaxDepth) fail(owner, "sequences nested deeper than " + std::to_string(kMaxDepth) + " levels");
        for (;;) {
            mAt = pos;
            unsigned char h[8];
            read(pos, h, 8, owner);
            const Tag t{u16(h, big), u16(h + 2, big)};
            const std::uint32_t len = u32(h + 4, big);
            pos += 8;
            if (t.is(0xFFFE, 0xE0DD)) return pos;
            if (!t.is(0xFFFE, 0xE000)) fail(owner, "expected a sequence item, found " + t.text());
            if (len == kUndefined) {
                pos = dataset(pos, 0, true, explicitVr, big, depth + 1);
            } else {
                need(pos + len, owner);
                pos += len;
            }
        }
    }

    std::uint32_t length(
        std::uint64_t pos, unsigned char* h, bool explicitVr, bool big, const Tag& t, std::uint64_t& header)
    {
        const bool item = t.group == 0xFFFE;
        if (!explicitVr || item) {
            header = 8;
            return u32(h + 4, big);
        }
        const char vr[3] = {char(h[4]), char(h[5]), 0};
        // Only the VRs of PS3.5 §6.2: GDCM asserts on others in the meta header
        // (found by fuzz/FuzzDicomPreflight) and guesses at them in the data set.
        static const char* kKnown[] = {"AE", "AS", "AT", "CS", "DA", "DS", "DT", "FD", "FL", "IS", "LO", "LT", "OB",
            "OD", "OF", "OL", "OV", "OW", "PN", "SH", "SL", "SQ", "SS", "ST", "SV", "TM", "UC", "UI", "UL", "UN", "UR",
            "US", "UT", "UV"};
        if (std::none_of(
                std::begin(kKnown), std::end(kKnown), [&](const char* k) { return std::strcmp(k, vr) == 0; })) {
            fail(t, "invalid value representation");
        }
        // A known VR that is not the one GDCM reads this element as (DicomElementRules.h).
        if (const std::string_view expected = expectedVr(t.group, t.element);
            !expected.empty() && expected.find(std::string_view(vr, 2)) == std::string_view::npos) {
            fail(t,
                "value representation '" + printable(std::string(vr, 2)) + "' where " + std::string(expected) +
                    " is required");
        }
        static const char* kLong[] = {"OB", "OD", "OF", "OL", "OV", "OW", "SQ", "SV", "UC", "UN", "UR", "UT", "UV"};
        for (const char* l : kLong) {
            if (std::strcmp(l, vr) == 0) {
                read(pos + 8, h + 8, 4, t);
                header = 12;
                return u32(h + 8, big);
            }
        }
        header = 8;
        return u16(h + 6, big);
    }

    /// Zero padding from @p pos to the end: noted, and the walk ends there.
    std::uint64_t padding(std::uint64_t pos)
    {
        mNotes.trailingPadding = mSize - pos;
        mNotes.paddingOffset = pos;
        return mSize;
    }

    /// True if every byte from @p pos to the end of the file is zero.
    bool zerosToEnd(std::uint64_t pos)
    {
        char buf[4096];
        mIn.clear();
        mIn.seekg(std::streamoff(pos));
        for (std::uint64_t left = mSize - pos; left > 0;) {
            const std::uint64_t n = std::min<std::uint64_t>(left, sizeof buf);
            if (!mIn.read(buf, std::streamsize(n))) return false;
            if (std::any_of(buf, buf + n, [](char c) { return c != 0; })) return false;
            left -= n;
        }
        return true;
    }

    /// Bytes pos .. pos + n of the file. Served from a window of the file read
    /// in one go: the walk reads every element header (8 or 12 bytes) and
    /// short values, and a seek and read of the stream for each cost a system
    /// call apiece (a sixth of a whole load's time on the shared CT).
    void read(std::uint64_t pos, void* out, std::uint64_t n, const Tag& t)
    {
        need(pos + n, t);
        if (pos < mWindowAt || pos + n > mWindowAt + mWindow.size()) {
            if (n > kWindowBytes) { // a long value: straight from the file
                mIn.clear();
                mIn.seekg(std::streamoff(pos));
                if (!mIn.read(static_cast<char*>(out), std::streamsize(n))) fail(t, "cannot read");
                return;
            }
            mWindow.resize(std::size_t(std::min<std::uint64_t>(kWindowBytes, mSize - pos)));
            mIn.clear();
            mIn.seekg(std::streamoff(pos));
            mIn.read(mWindow.data(), std::streamsize(mWindow.size()));
            mWindow.resize(std::size_t(std::max<std::streamsize>(mIn.gcount(), 0)));
            mWindowAt = pos;
            if (mWindow.size() < n) fail(t, "cannot read"); // the file shrank since its size was taken
        }
        std::memcpy(out, mWindow.data() + (pos - mWindowAt), std::size_t(n));
    }
    void need(std::uint64_t end, const Tag& t)
    {
        if (end > mSize) fail(t, "runs past the end of the file (truncated file)");
    }
    /// One line: the file, the element (when its tag was read) and the byte
    /// offset of its header, then what is wrong.
    [[noreturn]] void fail(const Tag& t, const std::string& what)
    {
        throw IoError(mFile.string() + ": " + (t.group || t.element ? t.text() + " " : std::string("element ")) +
            "at byte " + std::to_string(mAt) + ": " + what);
    }
    static std::uint16_t u16(const unsigned char* p, bool big)
    {
        return big ? std::uint16_t(p[0] << 8 | p[1]) : std::uint16_t(p[1] << 8 | p[0]);
    }
    static std::uint32_t u32(const unsigned char* p, bool big)
    {
        return big ? std::uint32_t(p[0]) << 24 | std::uint32_t(p[1]) << 16 | std::uint32_t(p[2]) << 8 | p[3]
                   : std::uint32_t(p[3]) << 24 | std::uint32_t(p[2]) << 16 | std::uint32_t(p[1]) << 8 | p[0];
    }

    const std::filesystem::path& mFile;
    std::ifstream& mIn;
    std::uint64_t mSize;
    DicomPreflightNotes& mNotes;
    static constexpr std::uint64_t kWindowBytes = 16384; ///< a typical header whole, little of the pixel data
    std::vector<char> mWindow;                           ///< bytes mWindowAt .. + size() of the file (read())
    std::uint64_t mWindowAt = 0;
    std::uint64_t mAt = 0;           ///< offset of the element being read, for messages
    std::uint64_t mDataSetStart = 0; ///< first byte after the meta header
    bool mFunctionalGroups = false;
    std::string mMetaSopClass, mSopClass;
    std::optional<std::pair<std::uint64_t, std::uint64_t>> mPixels;
};

/// The image storage classes voxhap reads: CT and MR, classic, enhanced and
/// legacy-converted enhanced. GDCM takes other classes down paths that assert
/// on what they do not expect (an ACR-NEMA recognition code, palettes,
/// ultrasound regions; fuzz findings), and none of them is a CT or MR volume.
bool readableSopClass(std::string uid)
{
    // GDCM drops one trailing padding byte and compares the rest exactly.
    if (!uid.empty() && (uid.back() == '\0' || uid.back() == ' ')) uid.pop_back();
    static const char* kClasses[] = {
        "1.2.840.10008.5.1.4.1.1.2",   // CT Image Storage
        "1.2.840.10008.5.1.4.1.1.2.1", // Enhanced CT Image Storage
        "1.2.840.10008.5.1.4.1.1.2.2", // Legacy Converted Enhanced CT Image Storage
        "1.2.840.10008.5.1.4.1.1.4",   // MR Image Storage
        "1.2.840.10008.5.1.4.1.1.4.1", // Enhanced MR Image Storage
        "1.2.840.10008.5.1.4.1.1.4.4", // Legacy Converted Enhanced MR Image Storage
    };
    return std::any_of(std::begin(kClasses), std::end(kClasses), [&](const char* k) { return uid == k; });
}

std::string withoutPadding(std::string uid)
{
    while (!uid.empty() && (uid.back() == '\0' || uid.back() == ' ')) uid.pop_back();
    return uid;
}

} // namespace

std::string sopClassName(const std::string& uid)
{
    // The classes a CD or PACS export puts beside CT and MR images (PS3.4 Annex B,
    // PS3.6 Annex A); anything else is named by its UID.
    static const std::pair<const char*, const char*> kNames[] = {
        {"1.2.840.10008.1.3.10", "Media Storage Directory (DICOMDIR)"},
        {"1.2.840.10008.5.1.4.1.1.7", "Secondary Capture Image Storage"},
        {"1.2.840.10008.5.1.4.1.1.7.1", "Multi-frame Single Bit Secondary Capture"},
        {"1.2.840.10008.5.1.4.1.1.7.2", "Multi-frame Grayscale Byte Secondary Capture"},
        {"1.2.840.10008.5.1.4.1.1.7.3", "Multi-frame Grayscale Word Secondary Capture"},
        {"1.2.840.10008.5.1.4.1.1.7.4", "Multi-frame True Color Secondary Capture"},
        {"1.2.840.10008.5.1.4.1.1.11.1", "Grayscale Softcopy Presentation State"},
        {"1.2.840.10008.5.1.4.1.1.11.2", "Color Softcopy Presentation State"},
        {"1.2.840.10008.5.1.4.1.1.66", "Raw Data Storage"},
        {"1.2.840.10008.5.1.4.1.1.66.4", "Segmentation Storage"},
        {"1.2.840.10008.5.1.4.1.1.88.11", "Basic Text SR"},
        {"1.2.840.10008.5.1.4.1.1.88.22", "Enhanced SR"},
        {"1.2.840.10008.5.1.4.1.1.88.33", "Comprehensive SR"},
        {"1.2.840.10008.5.1.4.1.1.88.67", "X-Ray Radiation Dose SR"},
        {"1.2.840.10008.5.1.4.1.1.104.1", "Encapsulated PDF Storage"},
        {"1.2.840.10008.5.1.4.1.1.481.1", "RT Image Storage"},
        {"1.2.840.10008.5.1.4.1.1.481.2", "RT Dose Storage"},
        {"1.2.840.10008.5.1.4.1.1.481.3", "RT Structure Set Storage"},
        {"1.2.840.10008.5.1.4.1.1.481.5", "RT Plan Storage"},
        {"1.2.840.10008.5.1.4.1.1.4.2", "MR Spectroscopy Storage"},
        {"1.2.840.10008.5.1.4.1.1.128", "Positron Emission Tomography Image Storage"},
        {"1.2.840.10008.5.1.4.1.1.20", "Nuclear Medicine Image Storage"},
        {"1.2.840.10008.5.1.4.1.1.6.1", "Ultrasound Image Storage"},
        {"1.2.840.10008.5.1.4.1.1.1", "Computed Radiography Image Storage"},
        {"1.2.840.10008.5.1.4.1.1.1.1", "Digital X-Ray Image Storage"},
        {"1.2.840.10008.5.1.4.1.1.9.1.1", "12-lead ECG Waveform Storage"},
        {"1.2.840.10008.5.1.4.1.1.9.1.2", "General ECG Waveform Storage"},
        {"1.3.12.2.1107.5.9.1", "Siemens CSA Non-Image Storage"},
    };
    const std::string u = withoutPadding(uid);
    for (const auto& [k, name] : kNames) {
        if (u == k) return name;
    }
    return u.empty() ? std::string("no SOP class") : "SOP class " + printable(u);
}

DicomKind preflightDicom(const std::filesystem::path& file, DicomPixelLocation* where, DicomPreflightNotes* notesOut)
{
    DicomPreflightNotes scratch;
    DicomPreflightNotes& notes = notesOut ? *notesOut : scratch;
    notes = {};
    std::error_code ec;
    const std::uint64_t size = std::filesystem::file_size(file, ec);
    if (ec) throw IoError(file.string() + ": cannot read (" + ec.message() + ")");
    std::ifstream in(file, std::ios::binary);
    char magic[132] = {};
    if (!in.read(magic, sizeof magic) || std::memcmp(magic + 128, "DICM", 4) != 0) return DicomKind::NotDicom;

    Walker walk(file, in, size, notes);
    std::string ts;
    const std::uint64_t start = walk.meta(132, ts);
    walk.setDataSetStart(start);
    // The meta header names the class: an object voxhap does not load is set
    // aside before its data set is walked, so that a report or a DICOMDIR
    // whose structure this walk would refuse cannot stop a load.
    const auto metaClass = walk.metaSopClass();
    if (!withoutPadding(metaClass.first).empty() && !readableSopClass(metaClass.first)) {
        notes.sopClass = withoutPadding(metaClass.first);
        notes.nonImageReason = sopClassName(notes.sopClass);
        return DicomKind::NonImage;
    }
    // The data set is walked in the syntax GDCM will read it in: one it knows,
    // named by the meta header. Without one GDCM guesses (a swapped-looking
    // first tag makes it read big endian) and could read other lengths than
    // this walk checked (fuzz finding: a 4 GB allocation).
    const gdcm::TransferSyntax syntax = gdcm::TransferSyntax::GetTSType(ts.c_str());
    if (ts.empty() || ts.find('\0') != std::string::npos || !syntax.IsValid()) {
        walk.refuse(Tag{0x0002, 0x0010}, "TransferSyntaxUID '" + printable(ts) + "' is missing or unknown");
    }
    if (syntax == gdcm::TransferSyntax::ImplicitVRBigEndianPrivateGE) {
        walk.refuse(
            Tag{0x0002, 0x0010}, "TransferSyntaxUID " + ts + " (GE private, mixed byte orders) is not supported");
    }
    // A deflated data set cannot be walked before GDCM inflates it; its meta
    // header must name the class (a readable one, from the test above).
    if (ts == "1.2.840.10008.1.2.1.99") {
        if (withoutPadding(metaClass.first).empty()) {
            walk.refuse(metaClass.second, "MediaStorageSOPClassUID is missing from a deflated file's meta header");
        }
        notes.sopClass = withoutPadding(metaClass.first);
        return DicomKind::Dicom;
    }
    const bool implicitVr = syntax.IsImplicit();
    const bool big = syntax.GetSwapCode() == gdcm::SwapCode::BigEndian;
    walk.dataset(start, size, false, !implicitVr, big, 0);
    notes.sopClass = withoutPadding(walk.sopClass().first);
    if (!readableSopClass(walk.sopClass().first)) {
        notes.nonImageReason = sopClassName(notes.sopClass);
        return DicomKind::NonImage;
    }
    if (where) {
        where->transferSyntax = ts;
        where->found = walk.pixels().has_value();
        if (walk.pixels()) std::tie(where->offset, where->length) = *walk.pixels();
    }
    if (walk.functionalGroups()) {
        // Structurally sound, so gdcm::Reader parses it safely; the values
        // ImageHelper asserts on are checked before anything else reads them.
        in.close();
        gdcm::Reader reader;
        reader.SetFileName(file.string().c_str());
        // The whole file, not up to the pixel data: GDCM keeps elements that
        // follow it out of order, and ImageHelper would see them (fuzz finding).
        if (!reader.Read()) throw IoError(file.string() + ": not a readable DICOM file");
        checkElementRules(reader.GetFile().GetDataSet(), file);
    }
    return DicomKind::Dicom;
}

} // namespace voxhap::volume
