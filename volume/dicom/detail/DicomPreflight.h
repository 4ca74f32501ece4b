// SPDX-License-Identifier: Apache-2.0
/// @file DicomPreflight.h
/// @brief A structural walk of a DICOM file's elements before GDCM sees it.
///
/// Debian's GDCM 3.0 is built with assertions: a file that ends inside an
/// element header or value aborts the whole process in GDCM's parser instead
/// of failing the read. This walk reads only element headers and checks that
/// every element, sequence item and pixel fragment fits inside the file, so
/// that such files are refused with one line naming the file and the tag.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

namespace voxhap::volume {

/// @brief What a file is, as far as loading volumes goes.
enum class DicomKind {
    NotDicom, ///< no "DICM" magic at byte 128 (raw datasets without a preamble are not read)
    Dicom,    ///< a CT or MR image object (Part 10) whose elements all fit inside the file
    NonImage, ///< a DICOM object that is not a CT or MR image: DICOMDIR, secondary capture, report, RT, raw data, ...
};

/// @brief Where a file's (7FE0,0010) PixelData lies, as the walk found it.
struct DicomPixelLocation {
    std::string transferSyntax; ///< (0002,0010), padding removed
    std::uint64_t offset = 0;   ///< first byte of the value
    std::uint64_t length = 0;   ///< value length [bytes]
    bool found = false;         ///< a top-level PixelData of defined length (native, not encapsulated)
};

/// @brief What the walk found besides the pixel data.
struct DicomPreflightNotes {
    std::string sopClass;              ///< (0002,0002), else (0008,0016), padding removed
    std::string nonImageReason;        ///< NonImage: the class in words and its UID
    std::string seriesUid;             ///< (0020,000E) if the walk got that far (also on a refusal)
    std::uint64_t trailingPadding = 0; ///< zero bytes after the last complete top-level element
    /// Short top-level values of the private groups that carry diffusion
    /// b-values — Siemens (0019,xxxx), GE (0043,xxxx), Philips (2001,xxxx) —
    /// keyed by (group << 16 | element), raw bytes: gdcm::Scanner reads no
    /// private tag, so the walk keeps them (creators included).
    std::map<std::uint32_t, std::string> privateValues;
    std::uint64_t paddingOffset = 0; ///< where they start
};

/// @brief Walk @p file's meta header and data set.
///
/// The SOP class is read from the meta header first: an object that is not a
/// CT or MR image is NonImage without walking its data set (CD exports hold
/// DICOMDIRs, reports and secondary captures beside the images; none of them
/// may stop a load). Zero bytes after the last complete top-level element are
/// trailing padding (some archives pad files to a block size): noted in
/// @p notes, not walked, and not corruption. Any other byte that does not
/// parse is.
/// @param where if given, receives the location of the pixel data
/// @param notes if given, receives the class, the series and the padding;
///        filled as far as the walk got when it throws
/// @return NotDicom for files without the DICM magic (nothing else is read)
/// @throw IoError naming the file, the element and its byte offset where the
///        file is damaged (an element that runs past the end, an invalid VR,
///        nesting deeper than 32 levels, ...)
DicomKind preflightDicom(
    const std::filesystem::path& file, DicomPixelLocation* where = nullptr, DicomPreflightNotes* notes = nullptr);

/// @brief The name of a SOP class voxhap does not load, for skip reports
/// ("Secondary Capture Image Storage", "Media Storage Directory (DICOMDIR)", ...);
/// the UID itself when unknown.
std::string sopClassName(const std::string& uid);

} // namespace voxhap::volume
