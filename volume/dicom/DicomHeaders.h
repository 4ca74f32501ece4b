// SPDX-License-Identifier: Apache-2.0
/// @file DicomHeaders.h
/// @brief The header fields voxhap reads from DICOM files (through
/// gdcm::Scanner, which stops before the pixel data), parsed and checked.
#pragma once

#include "core/Math.h"

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::volume {

/// @brief What tells the frames of one series apart beyond their position:
/// slices that differ in any of these are never stacked as one volume.
struct DicomFrameKey {
    std::string imageType;               ///< (0008,0008) or, per frame, (0008,9007) FrameType
    std::optional<int> echoNumber;       ///< (0018,0086)
    std::optional<double> echoTime;      ///< (0018,0081), per frame (0018,9082) [ms]
    std::optional<int> temporalPosition; ///< (0020,0100), per frame (0020,9128) TemporalPositionIndex
    std::optional<double> bValue; ///< (0018,9087), Siemens (0019,100C), GE (0043,1039), Philips (2001,1003) [s/mm²]
    std::optional<int> stack;     ///< per frame (0020,9056) StackID
    std::optional<int> acquisitionNumber; ///< (0020,0012): acquisition order, not a key by itself
    std::optional<double> triggerTime;    ///< (0018,1060) [ms]: acquisition order, not a key by itself
    std::optional<int> instanceNumber;    ///< (0020,0013): order of writing, the last tie-break

    /// @brief The fields that separate volumes (image type, echo, temporal
    /// position, b-value, stack), as a comparable string.
    std::string separating() const;
};

/// @brief One file's header: identity, grid and per-frame positions.
struct DicomHeader {
    std::filesystem::path file;
    std::string seriesUid, modality, seriesDescription, seriesNumber, imageType;
    int rows = 0, columns = 0, frames = 1; ///< of the slices (a mosaic's tiles); frames: slices in the file
    int storedRows = 0, storedColumns = 0,
        storedFrames = 1;                       ///< of the stored image (a mosaic: one image of many tiles)
    Vec3d rowDirection{1, 0, 0};                ///< (0020,0037) first triplet
    Vec3d columnDirection{0, 1, 0};             ///< (0020,0037) second triplet
    std::vector<Vec3d> framePositions;          ///< (0020,0032) per frame (a mosaic's tiles) [mm, LPS]
    double pixelSpacing[2] = {1, 1};            ///< (0028,0030): between rows, between columns [mm]
    double sliceThickness = 0;                  ///< (0018,0050), used only for one-slice series [mm]
    std::optional<double> spacingBetweenSlices; ///< (0018,0088) [mm]
    double slope = 1, intercept = 0;            ///< (0028,1053), (0028,1052)
    /// Enhanced multi-frame: each frame's rescale (0028,9145) and key; empty otherwise.
    std::vector<std::pair<double, double>> frameRescale; ///< slope, intercept
    std::vector<DicomFrameKey> frameKeys;
    DicomFrameKey key;                   ///< of a single-frame file (and the defaults of a multi-frame one)
    double gantryTilt = 0;               ///< (0018,1120) [deg]
    std::optional<double> padding;       ///< (0028,0120) in stored units
    std::optional<double> fieldStrength; ///< (0018,0087) MagneticFieldStrength [T], MR only
    int bitsAllocated = 16, bitsStored = 16, highBit = 15, pixelRepresentation = 0; ///< (0028,0100..0103)
    std::string transferSyntax;                                                     ///< (0002,0010)
    /// Where the preflight walk found a top-level PixelData of defined length
    /// (uncompressed): byte offset and length of its value; 0, 0 when not.
    std::uint64_t pixelOffset = 0, pixelLength = 0;
    std::uint64_t trailingPadding = 0; ///< zero bytes after the last element (noted, not an error)
    /// Siemens mosaic: slices tiled in the stored image; 0 when not a mosaic.
    int mosaicImages = 0;
    int mosaicTilesPerSide = 0; ///< tiles per row and per column of the mosaic
    /// The value of the last digit stored, for the tolerance of the checks
    /// (StoredPrecision.h): in (0020,0032), (0020,0037) and (0028,0030).
    double positionUnit = 0, orientationUnit = 0, spacingUnit = 0;
    bool complete = false; ///< completeDicomHeader has run
    /// The scanned values, keyed by (group << 16 | element), parsed by completeDicomHeader.
    std::map<std::uint32_t, std::string> tags;

    /// @brief ImageType or SeriesDescription names a T1 map (quantitative, ms).
    bool looksLikeT1Map() const;
    /// @brief The key of frame @p k (the file's own key for single-frame files).
    const DicomFrameKey& frameKey(int k) const { return frameKeys.empty() ? key : frameKeys[std::size_t(k)]; }
    /// @brief The scanned value of a tag, trimmed; empty if absent.
    std::string value(std::uint16_t group, std::uint16_t element) const;
};

/// @brief A file among the inputs that is not loaded, and why.
struct DicomSkippedFile {
    std::filesystem::path file;
    std::string category;  ///< "not DICOM", "damaged", "no image", or the SOP class's name
    std::string reason;    ///< one line; for damaged files the refusal (file, tag, byte offset)
    std::string seriesUid; ///< the series a damaged file belongs to, when its header got that far
};

/// @brief What a walk over the inputs found.
struct DicomScan {
    std::vector<DicomHeader> images;       ///< CT and MR image files, identity fields scanned
    std::vector<DicomSkippedFile> skipped; ///< everything else, with the reason
    /// Inflated copies of gzip-compressed files live as long as this (a private
    /// temporary folder, removed with the last copy of the scan).
    std::shared_ptr<void> unpacked;
    /// @brief @p message with the paths of inflated copies replaced by their
    /// .gz originals, so that refusals name the file the user has.
    std::string originalNames(std::string message) const;
    std::map<std::string, std::string> inflatedFrom; ///< inflated copy → original .gz path
};

/// @brief Walk @p inputs (directories recursively, in sorted order) and sort
/// every file into CT/MR images and skipped files. Nothing but a missing
/// input is fatal: non-DICOM files, DICOMDIRs, secondary captures, reports,
/// RT and raw-data objects, and damaged files are listed with their reason.
/// Files compressed with gzip (.dcm.gz) are inflated to a private temporary
/// folder first (the whole stream verified; at most @p inflateCapBytes each).
/// @throw IoError if an input is missing
DicomScan scanDicomInputs(
    const std::vector<std::filesystem::path>& inputs, std::uint64_t inflateCapBytes = std::uint64_t(4) << 30);

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
