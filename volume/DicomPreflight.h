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
#include <string>

namespace voxhap::volume {

/// @brief What the preamble says about a file.
enum class DicomKind {
    NotDicom, ///< no "DICM" magic at byte 128 (raw datasets without a preamble are not read)
    Dicom,    ///< a Part 10 file whose elements all fit inside it
};

/// @brief Where a file's (7FE0,0010) PixelData lies, as the walk found it.
struct DicomPixelLocation {
    std::string transferSyntax;  ///< (0002,0010), padding removed
    std::uint64_t offset = 0;    ///< first byte of the value
    std::uint64_t length = 0;    ///< value length [bytes]
    bool found = false;          ///< a top-level PixelData of defined length (native, not encapsulated)
};

/// @brief Walk @p file's meta header and data set.
/// @param where if given, receives the location of the pixel data
/// @return NotDicom for files without the DICM magic (nothing else is read)
/// @throw IoError naming the file and the first element that runs past its end
///        (or is malformed: odd VR, nesting deeper than 32 levels)
DicomKind preflightDicom(const std::filesystem::path& file, DicomPixelLocation* where = nullptr);

} // namespace voxhap::volume
