// SPDX-License-Identifier: Apache-2.0
/// @file DicomSeries.h
/// @brief Read a DICOM series (a directory or a list of files) into a Volume,
/// through GDCM.
///
/// Files are grouped by SeriesInstanceUID; slices are ordered by their
/// position along the slice normal (ImagePositionPatient · normal), never by
/// file name; the slice step comes from the positions, not SliceThickness.
/// CT becomes the `hu` grid (Rescale Slope/Intercept applied per slice), MR
/// the `t1` grid. Air is deactivated; every other value is exact.
#pragma once

#include "volume/TissueTable.h"
#include "volume/Volume.h"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace voxhap::volume {

/// @brief One series found among the inputs.
struct DicomSeriesInfo {
    std::string uid;          ///< SeriesInstanceUID
    std::string modality;     ///< "CT", "MR", ...
    std::string description;  ///< SeriesDescription, may be empty
    std::string number;       ///< SeriesNumber, may be empty
    int rows = 0, columns = 0;
    std::int64_t slices = 0;  ///< frames over all files of the series
    std::vector<std::filesystem::path> files;
};

/// @brief What to do when the slices do not form a uniform grid.
enum class IrregularSlices {
    Refuse,   ///< throw, naming the problem (default)
    Resample, ///< interpolate onto a uniform grid along the normal (values no longer exact)
};

/// @brief Choices for loadDicom.
struct DicomOptions {
    /// SeriesInstanceUID, or a 1-based index into listDicomSeries' order;
    /// empty: the largest CT series (else the largest series).
    std::string series;
    IrregularSlices irregular = IrregularSlices::Refuse;
    /// CT voxels below this become inactive air [HU]. Air is -1000 with noise
    /// of a few tens of HU; lung parenchyma reaches about -910 (physics.md
    /// §5.2), so -950 keeps lung active and drops the air around the patient.
    float airHu = -950.0f;
    /// MR voxels below this become inactive (background, noise) [t1 units].
    float airT1 = 0.0f;
    /// Refuse, before allocating, a series whose grid could exceed this [bytes].
    std::uint64_t memoryCapBytes = std::uint64_t(4) << 30;
    /// MR only: the series holds T1 maps [ms] even if its headers do not say so.
    bool t1Map = false;
    /// MR only: T1-weighted intensities become T1 [ms] by the per-scan rule of
    /// physics.md §5.1 (T1Normalisation.h). If the scan shows no fat and muscle
    /// classes, or this is off, the raw intensities stay, labelled as such,
    /// and the force models do not read them as T1.
    bool normaliseT1Weighted = true;
    /// MR only: the field strength when (0018,0087) is absent.
    FieldStrength assumedField = FieldStrength::T1_5;
    /// Called with the fraction done (0..1) as slices load; may be empty.
    std::function<void(double)> progress;
};

/// @brief Figures of one load, for reports and benchmarks.
struct DicomLoadReport {
    DicomSeriesInfo series;
    std::vector<DicomSeriesInfo> allSeries; ///< every series found among the inputs
    double seconds = 0;                     ///< wall time of the whole load [s]
    double scanSeconds = 0;                 ///< of which: preflight walk and header scan [s]
    double decodeSeconds = 0;               ///< of which: GDCM decode and rescale to float [s]
    double sparseSeconds = 0;               ///< of which: dense slabs into the sparse grid [s]
    std::int64_t denseVoxels = 0;
    std::int64_t activeVoxels = 0;
    std::uint64_t memoryBytes = 0;          ///< the grid's memory [bytes]
    bool resampled = false;
    std::string irregularity;               ///< why the slices were resampled, empty if not
};

/// @brief True if @p path is a directory or a file that starts like DICOM
/// (the "DICM" magic at byte 128).
bool looksLikeDicom(const std::filesystem::path& path);

/// @brief The series among @p inputs (directories are searched recursively),
/// largest first. Non-DICOM files are skipped.
/// @throw IoError if no input holds a DICOM image
std::vector<DicomSeriesInfo> listDicomSeries(const std::vector<std::filesystem::path>& inputs);

/// @brief Load one series as a Volume in LPS millimetres.
/// @throw IoError naming the file and the field (tag) at fault
/// @throw ValueError for a choice that makes no sense (unknown series)
Volume loadDicom(const std::vector<std::filesystem::path>& inputs, const DicomOptions& options = {},
                 DicomLoadReport* report = nullptr);

} // namespace voxhap::volume
