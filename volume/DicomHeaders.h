// SPDX-License-Identifier: Apache-2.0
/// @file DicomHeaders.h
/// @brief The header fields voxhap reads from DICOM files (through
/// gdcm::Scanner, which stops before the pixel data), parsed and checked.
#pragma once

#include "volume/Math.h"

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::volume {

/// @brief One file's header: identity, grid and per-frame positions.
struct DicomHeader {
    std::filesystem::path file;
    std::string seriesUid, modality, seriesDescription, seriesNumber, imageType;
    int rows = 0, columns = 0, frames = 1;
    Vec3d rowDirection{1, 0, 0};        ///< (0020,0037) first triplet
    Vec3d columnDirection{0, 1, 0};     ///< (0020,0037) second triplet
    std::vector<Vec3d> framePositions;  ///< (0020,0032) per frame [mm, LPS]
    double pixelSpacing[2] = {1, 1};    ///< (0028,0030): between rows, between columns [mm]
    double sliceThickness = 0;          ///< (0018,0050), used only for one-slice series [mm]
    double slope = 1, intercept = 0;    ///< (0028,1053), (0028,1052)
    double gantryTilt = 0;              ///< (0018,1120) [deg]
    std::optional<double> padding;      ///< (0028,0120) in stored units
    std::optional<double> fieldStrength; ///< (0018,0087) MagneticFieldStrength [T], MR only
    int bitsAllocated = 16, bitsStored = 16, pixelRepresentation = 0; ///< (0028,0100), (0028,0101), (0028,0103)
    std::string transferSyntax;          ///< (0002,0010)
    /// Where the preflight walk found a top-level PixelData of defined length
    /// (uncompressed): byte offset and length of its value; 0, 0 when not.
    std::uint64_t pixelOffset = 0, pixelLength = 0;
    /// The scanned values, keyed by (group << 16 | element), parsed by completeDicomHeader.
    std::map<std::uint32_t, std::string> tags;

    /// @brief ImageType or SeriesDescription names a T1 map (quantitative, ms).
    bool looksLikeT1Map() const;
};

/// @brief The identity fields (series, modality, size, frames) of every DICOM
/// image among @p inputs; directories are searched recursively, in sorted
/// order; files that are not DICOM images are skipped.
/// @throw IoError if an input is missing or no DICOM image is found
std::vector<DicomHeader> scanDicomHeaders(const std::vector<std::filesystem::path>& inputs);

/// @brief Parse and check the geometry fields of a scanned header (and, for
/// multi-frame files, read their functional groups).
/// @throw IoError naming the file and the tag that is missing or malformed
void completeDicomHeader(DicomHeader& h);

/// @brief All fields of the given files, geometry parsed and checked.
/// @throw IoError naming the file and the tag that is missing or malformed
std::vector<DicomHeader> readSeriesHeaders(const std::vector<std::filesystem::path>& files);

/// @brief @p h must share @p first's orientation, rows, columns and pixel spacing.
/// @throw IoError naming h's file and the differing tag
void checkSameGrid(const DicomHeader& first, const DicomHeader& h);

} // namespace voxhap::volume
