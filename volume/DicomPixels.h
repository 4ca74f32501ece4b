// SPDX-License-Identifier: Apache-2.0
/// @file DicomPixels.h
/// @brief Decode the pixel data of one DICOM file through GDCM into floats,
/// with the stored-value checks GDCM does not make (truncation, unused bits,
/// padding).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

namespace voxhap::volume {

/// @brief Stored pixel values of every frame of a file, as float, before
/// rescaling: frames × rows × columns, column fastest.
struct DicomFrames {
    int rows = 0, columns = 0, frames = 0;
    std::vector<float> values;
    /// Stored values equal to PixelPaddingValue (0028,0120), flagged so that
    /// the caller can make them air; empty when the file has no padding value.
    std::vector<std::uint8_t> padding;
    std::vector<char> raw; ///< decoding scratch, kept so that a reused instance does not reallocate
};

/// @brief Silence GDCM's own warnings and errors: voxhap reports its own, one line each.
void quietGdcm();

/// @brief Decode @p file.
/// @param paddingValue PixelPaddingValue from the header, if any (stored units)
/// @throw IoError naming the file and the field: unreadable file, unsupported
///        transfer syntax, colour images, truncated pixel data
DicomFrames decodeDicomFrames(const std::filesystem::path& file, std::optional<double> paddingValue);

/// @brief As above, into @p out, reusing its buffers: a thread that decodes
/// many slices keeps one instance and avoids fresh page-faulting allocations.
void decodeDicomFrames(const std::filesystem::path& file, std::optional<double> paddingValue, DicomFrames& out);

} // namespace voxhap::volume
