// SPDX-License-Identifier: Apache-2.0
/// @file VolumeFile.h
/// @brief Load or save a Volume whatever the format: the one entry point the
/// command line uses. The format comes from the path: a directory or a file
/// with the DICOM magic is DICOM, otherwise the extension decides.
#pragma once

#include "volume/Volume.h"
#include "volume/dicom/DicomSeries.h"
#include "volume/io/RasterReader.h"

#include <filesystem>
#include <string>

namespace voxhap::volume {

enum class VolumeFormat {
    Dicom,
    Vdb,
    Nrrd,
    Nifti,
    MetaImage,
    Unknown
};

/// @brief The format of @p path, from its kind, magic and extension.
VolumeFormat formatOf(const std::filesystem::path& path);
std::string formatName(VolumeFormat f);

/// @brief What a volume in a format without a modality (NIfTI, NRRD,
/// MetaImage) holds, when the user says.
enum class DeclaredModality {
    Infer, ///< a BIDS sidecar's Modality, else the data (ModalityInference.h)
    Ct,    ///< Hounsfield units
    Mr,    ///< MR intensities (the weighting from a sidecar, --t1-weighted or --t1-map)
};

/// @brief Options of the readers. The air thresholds, memory cap, progress
/// and the MR choices (t1Map, t1Weighted, normalisation, background, assumed
/// field) in `dicom` apply to every format.
struct LoadOptions {
    DicomOptions dicom;
    /// Formats that do not say what they hold (NRRD, MetaImage, NIfTI).
    DeclaredModality modality = DeclaredModality::Infer;
};

/// @brief The raster-reader options that @p o implies (values into hu).
RasterOptions rasterOptions(const LoadOptions& o);

/// @brief Load @p path. @p report is filled for DICOM inputs.
///
/// NIfTI, NRRD and MetaImage carry no modality: it comes from the user
/// (options.modality), else a BIDS sidecar beside the file (x.json, as
/// dcm2niix writes it), else the values (ModalityInference.h); the metadata
/// say which and why (modalitySource, modalityReason). MR then goes through
/// assignMrMaterial (MrMaterial.h) with the sidecar's weighting, or the
/// user's declaration, or none: an intensity grid of unknown weighting.
/// @throw IoError naming the file and the field; for an unknown format, and
///        for values that are neither CT nor MR, naming --channel
Volume loadVolume(
    const std::filesystem::path& path, const LoadOptions& options = {}, DicomLoadReport* report = nullptr);

/// @brief Save @p v to a .vdb (every grid) or .nrrd (hu, else t1, else label).
/// @throw IoError naming the file
void saveVolume(const Volume& v, const std::filesystem::path& file);

} // namespace voxhap::volume
