// SPDX-License-Identifier: Apache-2.0
/// @file DicomPixels.h
/// @brief Decode the pixel data of one DICOM file through GDCM into floats,
/// with the stored-value checks GDCM does not make (truncation, unused bits,
/// padding).
#pragma once

#include "volume/dicom/DicomHeaders.h"
#include "volume/io/RasterLayout.h"

#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

namespace voxhap::volume {

/// @brief The stored samples of every frame of a file, as GDCM decoded them:
/// frames × rows × columns, column fastest, in the file's sample type.
struct DicomFrames {
    int rows = 0, columns = 0, frames = 0;
    SampleType type = SampleType::Int16;
    int bitsStored = 0;    ///< (0028,0101); other bits may hold overlays
    int highBit = -1;      ///< (0028,0102); -1: bitsStored − 1 (the value in the low bits)
    std::vector<char> raw; ///< kept between calls so that a reused instance does not reallocate
};

/// @brief Frame @p frame of @p f as rescaled floats: slope·stored + intercept
/// (computed in double: exact for the integer values and rescales CT has),
/// stored values equal to @p padding (PixelPaddingValue) become @p air.
/// One pass over the samples; unused high bits are masked (sign-extended).
void frameToFloat(const DicomFrames& f, int frame, double slope, double intercept, std::optional<double> padding,
    float air, float* out);

/// @brief As frameToFloat, for @p count samples of frame @p frame from sample
/// @p first on (one image row, for instance).
void samplesToFloat(const DicomFrames& f, int frame, std::size_t first, std::size_t count, double slope,
    double intercept, std::optional<double> padding, float air, float* out);

/// @brief As samplesToFloat, for @p count samples at @p raw laid out as
/// @p f's (type and bits; f.raw is not used): samples read from a file by
/// some other route than DicomFrames.
void rawSamplesToFloat(const DicomFrames& f, const char* raw, std::size_t count, double slope, double intercept,
    std::optional<double> padding, float air, float* out);

/// @brief Silence GDCM's own warnings and errors: voxhap reports its own, one line each.
void quietGdcm();

/// @brief Decode @p file.
/// @throw IoError naming the file and the field: unreadable file, unsupported
///        transfer syntax, colour images, truncated pixel data
DicomFrames decodeDicomFrames(const std::filesystem::path& file);

/// @brief Read the samples of an uncompressed little-endian file straight
/// from where the preflight walk found its pixel data, without GDCM: for
/// these syntaxes GDCM's decode is a copy of the same bytes (the test
/// DicomNative compares both on every file of the real CT), and skipping its
/// full data-set parse makes it the cheapest step of a load.
/// @return false when @p h is not such a file (compressed, big endian,
///         encapsulated, 64-bit samples): decode it with GDCM instead
/// @throw IoError naming the file when the value is shorter than the image
bool readNativeFrames(const DicomHeader& h, DicomFrames& out);

/// @brief What readNativeFrames would read, without reading it: @p out's
/// type, bits and dimensions (its raw samples untouched), for a loader that
/// reads the samples from h.pixelOffset itself, a few rows at a time.
/// @return false when @p h is not such a file
/// @throw IoError naming the file when the value is shorter than the image
bool nativeFrameLayout(const DicomHeader& h, DicomFrames& out);

/// @brief As decodeDicomFrames(file), into @p out, reusing its buffers: a thread that decodes
/// many slices keeps one instance and avoids fresh page-faulting allocations.
///
/// GDCM runs in a decoder process of its own (DicomDecodeProcess.h), started
/// for this call; a load keeps one for all its files.
void decodeDicomFrames(const std::filesystem::path& file, DicomFrames& out);

/// @brief The decode itself, in this process (what the decoder process runs).
void decodeDicomFramesInProcess(const std::filesystem::path& file, DicomFrames& out);

} // namespace voxhap::volume
