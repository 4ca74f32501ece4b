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

#include <filesystem>

namespace voxhap::volume {

/// @brief What the preamble says about a file.
enum class DicomKind {
    NotDicom, ///< no "DICM" magic at byte 128 (raw datasets without a preamble are not read)
    Dicom,    ///< a Part 10 file whose elements all fit inside it
};

/// @brief Walk @p file's meta header and data set.
/// @return NotDicom for files without the DICM magic (nothing else is read)
/// @throw IoError naming the file and the first element that runs past its end
///        (or is malformed: odd VR, nesting deeper than 32 levels)
DicomKind preflightDicom(const std::filesystem::path& file);

} // namespace voxhap::volume
