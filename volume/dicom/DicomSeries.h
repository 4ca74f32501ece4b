// SPDX-License-Identifier: Apache-2.0
/// @file DicomSeries.h
/// @brief Read DICOM as users bring it — a CD or PACS export, a flat folder of
/// several series, a 4D series, files gzip-compressed — into a Volume, through GDCM.
///
/// - Folders are walked recursively. Only CT and MR image objects are read;
///   DICOMDIRs, secondary captures, reports, RT, presentation-state and raw
///   data objects, non-DICOM files and damaged files are set aside with their
///   reason (DicomScan), never fatal unless they belong to the series loaded.
/// - Files are grouped by SeriesInstanceUID; a series is split into its 3D
///   volumes (DicomVolumes.h); slices are ordered by position along the
///   normal, never by file name; the slice step comes from the positions.
/// - CT becomes the `hu` grid (rescale applied per slice); MR goes through
///   assignMrMaterial (MrMaterial.h): `t1` only for T1 maps and T1-weighted
///   series, `intensity` otherwise, the air background inactive.
/// - Checks of positions, orientation and spacing tolerate what the stored
///   digits cannot resolve (StoredPrecision.h); every refusal is one line
///   naming the file, the tag and, where it helps, the option that resolves it.
#pragma once

#include "core/Progress.h"
#include "volume/TissueTable.h"
#include "volume/Volume.h"
#include "volume/dicom/DicomHeaders.h"
#include "volume/mr/MrMaterial.h"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace voxhap::volume {

/// @brief One series found among the inputs, as the series table shows it.
struct DicomSeriesInfo {
    int index = 0;             ///< 1-based position in the table (ordered by SeriesNumber, then UID)
    std::string uid;           ///< SeriesInstanceUID
    std::string modality;      ///< "CT", "MR", ...
    std::string description;   ///< SeriesDescription, may be empty
    std::string number;        ///< SeriesNumber, may be empty
    int rows = 0, columns = 0; ///< of a slice (a mosaic's tile)
    std::int64_t slices = 0;   ///< slices over all files of the series (a mosaic's tiles count)
    std::vector<std::filesystem::path> files;
    std::string orientation;       ///< "axial", "sagittal", "coronal" or "oblique" (from the slice normal)
    Vec3d spacing{0, 0, 0};        ///< between columns, between rows, slice step [mm]; 0 where unknown
    std::size_t volumes = 0;       ///< 3D volumes in the series; 0 if it could not be split
    std::string volumeShape;       ///< "13 volumes × 25 slices"
    std::string volumeSummary;     ///< "1: b=0, 2–13: b=1000"
    std::string separatedBy;       ///< what separates the volumes: "b-value, acquisition order"
    std::string weighting;         ///< MR: the weighting rule's verdict ("T1-weighted", ...)
    std::string weightingReason;   ///< MR: why
    std::int64_t voxels = 0;       ///< voxels of one volume (rows × columns × its slices)
    std::int64_t damagedFiles = 0; ///< damaged files that belong to it (set aside)
    /// Empty if the series loads as one 3D volume with the options given;
    /// otherwise why not, naming the option that would load it.
    std::string problem;
};

/// @brief What to do when the slices do not form a uniform grid.
enum class IrregularSlices {
    Refuse,   ///< throw, naming the problem (default)
    Resample, ///< interpolate onto a uniform grid along the normal (values no longer exact)
};

/// @brief Choices for loadDicom.
struct DicomOptions {
    /// Which series: its SeriesInstanceUID, its SeriesNumber, its index in the
    /// table ("#3", or a plain number when that names no other series'
    /// SeriesNumber); empty: the default rule (chooseDefaultSeries).
    std::string series;
    /// Which volume of a 4D series, from 1 (the table's order); 0: the series
    /// must hold exactly one.
    std::size_t volume = 0;
    IrregularSlices irregular = IrregularSlices::Refuse;
    /// Load the rest of a series when some of its files cannot be read
    /// (listed in the report); the usual gap checks then apply.
    bool skipBad = false;
    /// CT voxels below this become inactive air [HU]. Air is -1000 with noise
    /// of a few tens of HU; lung parenchyma reaches about -910 (physics.md
    /// §5.2), so -950 keeps lung active and drops the air around the patient.
    float airHu = -950.0f;
    /// MR voxels at or below this become inactive before the background rule
    /// [scanner units] (magnitude images hold no tissue at zero).
    float airT1 = 0.0f;
    /// Refuse, before allocating, a series whose grid could exceed this [bytes].
    std::uint64_t memoryCapBytes = std::uint64_t(4) << 30;
    /// MR: the values are T1 maps [ms] whatever the headers say.
    bool t1Map = false;
    /// MR: declare the series T1-weighted whatever the headers say (recorded).
    bool t1Weighted = false;
    /// MR only: T1-weighted intensities become T1 [ms] by the per-scan rule of
    /// physics.md §5.1 (T1Normalisation.h). If the scan shows no fat and muscle
    /// classes, or this is off, the values stay an intensity grid.
    bool normaliseT1Weighted = true;
    /// MR only: make the air around the body inactive (MrBackground.h).
    bool removeMrBackground = true;
    /// MR only: the field strength when (0018,0087) is absent.
    FieldStrength assumedField = FieldStrength::T1_5;
    /// Called with the fraction done (0..1) as slices load; may be empty.
    Progress progress;
};

/// @brief Every series among the inputs and every file set aside.
struct DicomCatalog {
    std::vector<DicomSeriesInfo> series;   ///< the series table, in index order
    std::vector<DicomSkippedFile> skipped; ///< files not read, with the reason
    DicomScan scan;                        ///< the scanned headers (and any inflated copies)
    /// Headers of each series (same order as `series`), geometry completed;
    /// empty for a series whose headers could not be completed (see its problem).
    std::vector<std::vector<DicomHeader>> headers;
};

/// @brief Figures of one load, for reports and benchmarks.
struct DicomLoadReport {
    DicomSeriesInfo series;
    std::vector<DicomSeriesInfo> allSeries;   ///< every series found among the inputs
    std::vector<DicomSkippedFile> skipped;    ///< files among the inputs that were not read, with the reason
    std::vector<DicomSkippedFile> skippedBad; ///< files of this series left out under skipBad
    std::size_t volume = 0;                   ///< the volume loaded (from 1); 0 when the series has one
    std::string chosenBecause;                ///< why this series (the default rule, or the option)
    double seconds = 0;                       ///< wall time of the whole load [s]
    double scanSeconds = 0;                   ///< of which: preflight walk and header scan [s]
    double decodeSeconds = 0;                 ///< of which: decoding whole files (GDCM, multi-frame, mosaics) [s]
    /// of which: samples into the sparse grid [s]; for uncompressed single-frame
    /// files this includes reading them, which overlaps the conversion
    double sparseSeconds = 0;
    std::int64_t denseVoxels = 0;
    std::int64_t activeVoxels = 0;
    std::uint64_t memoryBytes = 0; ///< the grid's memory [bytes]
    bool resampled = false;
    std::string irregularity;             ///< why the slices were resampled, empty if not
    std::string interpolation;            ///< how they were, empty if not
    std::int64_t sourceVoxelsOutside = 0; ///< source voxels whose centre lies outside the resampled grid
    std::int64_t paddedFiles = 0;         ///< files with zero padding after their last element (accepted)
    std::optional<MrMaterialReport> mr;   ///< MR: what the image became
};

/// @brief True if @p path is a directory or a file that starts like DICOM
/// (the "DICM" magic at byte 128) or like gzip (a .dcm.gz).
bool looksLikeDicom(const std::filesystem::path& path);

/// @brief Scan @p inputs, build the series table and decide, for each series,
/// whether it loads as one 3D volume under @p options.
/// @throw IoError if an input is missing
DicomCatalog catalogDicom(const std::vector<std::filesystem::path>& inputs, const DicomOptions& options = {});

/// @brief The series among @p inputs (the catalog's table).
/// @throw IoError if no input holds a DICOM image
std::vector<DicomSeriesInfo> listDicomSeries(const std::vector<std::filesystem::path>& inputs);

/// @brief The default series of a catalog: the largest series that loads as
/// one 3D volume under the catalog's options, CT first, then T1 maps and
/// T1-weighted MR, then other MR; ties go to the lower index. nullptr if none.
const DicomSeriesInfo* chooseDefaultSeries(const DicomCatalog& catalog);

/// @brief Load one series (one volume of it) as a Volume in LPS millimetres.
/// @throw IoError naming the file and the field (tag) at fault, or the folder
///        and the option that resolves the problem
/// @throw ValueError for a choice that makes no sense (unknown or ambiguous series)
Volume loadDicom(const std::vector<std::filesystem::path>& inputs, const DicomOptions& options = {},
    DicomLoadReport* report = nullptr);

} // namespace voxhap::volume
