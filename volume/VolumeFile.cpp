// SPDX-License-Identifier: Apache-2.0
/// @file VolumeFile.cpp
/// @brief Format dispatch for loading and saving volumes.

#include "volume/VolumeFile.h"

#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/io/MetaImageFile.h"
#include "volume/io/ModalityInference.h"
#include "volume/io/NiftiFile.h"
#include "volume/io/NrrdFile.h"
#include "volume/io/VdbFile.h"
#include "volume/mr/MrMaterial.h"
#include "volume/mr/MrWeighting.h"

#include <openvdb/tools/ChangeBackground.h>
#include <openvdb/tools/Prune.h>
#include <openvdb/tree/LeafManager.h>

#include <algorithm>
#include <cctype>
#include <limits>

namespace voxhap::volume {

namespace {

std::string lowerExtension(const std::filesystem::path& p)
{
    std::string e = p.extension().string();
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return e;
}

} // namespace

VolumeFormat formatOf(const std::filesystem::path& path)
{
    const std::string ext = lowerExtension(path);
    std::string name = path.filename().string();
    std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (ext == ".nii" || ext == ".hdr" || (name.size() > 7 && name.compare(name.size() - 7, 7, ".nii.gz") == 0)) {
        return VolumeFormat::Nifti;
    }
    if (ext == ".vdb") return VolumeFormat::Vdb;
    if (ext == ".mha" || ext == ".mhd") return VolumeFormat::MetaImage;
    if (ext == ".nrrd") return VolumeFormat::Nrrd;
    if (ext == ".dcm" || ext == ".dicom" || ext == ".ima") return VolumeFormat::Dicom;
    if (std::filesystem::exists(path) && looksLikeDicom(path)) return VolumeFormat::Dicom;
    return VolumeFormat::Unknown;
}

std::string formatName(VolumeFormat f)
{
    switch (f) {
    case VolumeFormat::Dicom:
        return "dicom";
    case VolumeFormat::Vdb:
        return "vdb";
    case VolumeFormat::Nrrd:
        return "nrrd";
    case VolumeFormat::Nifti:
        return "nifti";
    case VolumeFormat::MetaImage:
        return "metaimage";
    case VolumeFormat::Unknown:
        break;
    }
    return "unknown";
}

RasterOptions rasterOptions(const LoadOptions& o)
{
    RasterOptions r;
    r.channel = Channel::Hu;
    r.airHu = o.dicom.airHu;
    r.airT1 = o.dicom.airT1;
    r.memoryCapBytes = o.dicom.memoryCapBytes;
    r.progress = o.dicom.progress;
    return r;
}

namespace {

/// Give the raw grid (every voxel active, background −1000) its channel's
/// background and make the voxels below @p airBelow inactive: CT air, or the
/// zeros and negatives of an MR image.
Volume::GridPtr withAir(const Volume& raw, float background, float airBelow, bool atOrBelow)
{
    FloatGrid::Ptr g = huGrid(raw)->deepCopy();
    openvdb::tools::changeBackground(g->tree(), background);
    openvdb::tree::LeafManager<FloatGrid::TreeType>(g->tree()).foreach (
        [&](FloatGrid::TreeType::LeafNodeType& leaf, std::size_t) {
            for (auto it = leaf.beginValueOn(); it; ++it) {
                if (*it < airBelow || (atOrBelow && *it == airBelow)) {
                    it.setValue(background);
                    it.setValueOff();
                }
            }
        });
    for (auto it = g->tree().beginValueOn(); it; ++it) { // tiles
        if (!it.isVoxelValue() && (*it < airBelow || (atOrBelow && *it == airBelow))) {
            it.setValue(background);
            it.setActiveState(false);
        }
    }
    openvdb::tools::pruneInactive(g->tree());
    return g;
}

/// NIfTI, NRRD, MetaImage: read every value, decide CT or MR, then the material.
Volume loadRasterVolume(const std::filesystem::path& path, VolumeFormat format, const LoadOptions& options)
{
    RasterOptions all = rasterOptions(options);
    all.airHu = -std::numeric_limits<float>::max(); // keep every voxel: the census needs the air
    Volume raw = format == VolumeFormat::Nrrd ? loadNrrd(path, all)
        : format == VolumeFormat::Nifti       ? loadNifti(path, all)
                                              : loadMetaImage(path, all);
    const VolumeMetadata& rawMd = raw.metadata();
    // A voxhap NRRD names its channel: t1, label and intensity are read as they
    // are, and hu is CT by the file's own word (NrrdFile.h).
    if (!raw.has(Channel::Hu)) return raw;
    const bool declared = rawMd.modalitySource == FactSource::Header;
    const std::string name = path.string();

    std::optional<BidsSidecar> sidecar = readBidsSidecarBeside(path);
    ModalityGuess::Kind kind = ModalityGuess::Kind::Unknown;
    std::string why = rawMd.modalityReason;
    FactSource from = FactSource::Header;
    if (declared) {
        kind = ModalityGuess::Kind::Ct;
    } else if (options.modality != DeclaredModality::Infer) {
        kind = options.modality == DeclaredModality::Ct ? ModalityGuess::Kind::Ct : ModalityGuess::Kind::Mr;
        why = std::string("declared by the user (--channel ") + (kind == ModalityGuess::Kind::Ct ? "hu)" : "mr)");
        from = FactSource::User;
    } else if (sidecar && (sidecar->modality == "MR" || sidecar->modality == "CT")) {
        kind = sidecar->modality == "CT" ? ModalityGuess::Kind::Ct : ModalityGuess::Kind::Mr;
        why = "Modality " + sidecar->modality + " in the BIDS sidecar " + sidecar->file.filename().string();
        from = FactSource::Sidecar;
    } else {
        const ModalityGuess guess = inferModality(*raw.grid(Channel::Hu));
        kind = guess.kind;
        why = "inferred from the data: " + guess.reason;
        from = FactSource::Data;
        if (kind == ModalityGuess::Kind::Unknown) {
            throw IoError(
                name + ": modality: " + guess.reason + "; declare it with --channel hu (CT) or --channel mr (MR)");
        }
    }

    Volume v(raw.transformPtr()->copy(), raw.indexBox());
    VolumeMetadata& md = v.metadata();
    md = rawMd;
    md.modalitySource = from;
    md.modalityReason = why;
    if (kind == ModalityGuess::Kind::Ct) {
        v.setGrid(Channel::Hu, withAir(raw, kAirHu, options.dicom.airHu, false));
        md.modality = "CT";
        return v;
    }
    v.setGrid(Channel::Intensity, withAir(raw, kAirIntensity, options.dicom.airT1, true));
    md.modality = "MR";
    MrWeighting weighting;
    if (sidecar) {
        weighting = classifyMrWeighting(sidecar->fields);
    } else {
        weighting.kind = MrWeightingKind::Unknown;
        weighting.name = std::string(mrWeightingName(MrWeightingKind::Unknown));
        weighting.reason = "no BIDS sidecar (" + bidsSidecarPath(path).filename().string() +
            ") beside the file: declare a T1-weighted image with --t1-weighted, a T1 map with --t1-map";
    }
    MrMaterialOptions mo;
    mo.t1Map = options.dicom.t1Map;
    mo.t1Weighted = options.dicom.t1Weighted;
    mo.normaliseT1Weighted = options.dicom.normaliseT1Weighted;
    mo.removeBackground = options.dicom.removeMrBackground;
    recordFieldStrength(
        md, sidecar ? sidecar->fieldStrengthT : std::nullopt, FactSource::Sidecar, options.dicom.assumedField);
    assignMrMaterial(v, weighting, mo, name);
    return v;
}

} // namespace

Volume loadVolume(const std::filesystem::path& path, const LoadOptions& options, DicomLoadReport* report)
{
    if (!std::filesystem::exists(path)) throw IoError(path.string() + ": no such file or directory");
    switch (const VolumeFormat f = formatOf(path)) {
    case VolumeFormat::Dicom:
        return loadDicom({path}, options.dicom, report);
    case VolumeFormat::Vdb:
        return loadVdb(path, options.dicom.memoryCapBytes);
    case VolumeFormat::Nrrd:
    case VolumeFormat::Nifti:
    case VolumeFormat::MetaImage:
        return loadRasterVolume(path, f, options);
    case VolumeFormat::Unknown:
        break;
    }
    throw IoError(path.string() +
        ": unknown format (expected a DICOM directory or file, .nii, .nii.gz, .nrrd, .mha, .mhd or .vdb)");
}

void saveVolume(const Volume& v, const std::filesystem::path& file)
{
    switch (formatOf(file)) {
    case VolumeFormat::Vdb:
        saveVdb(v, file);
        return;
    case VolumeFormat::Nrrd: {
        const Channel c = v.has(Channel::Hu) ? Channel::Hu
            : v.has(Channel::T1)             ? Channel::T1
            : v.has(Channel::Intensity)      ? Channel::Intensity
                                             : Channel::Label;
        try {
            saveNrrd(v, c, file);
        } catch (const ValueError& e) {
            throw IoError(e.what());
        }
        return;
    }
    default:
        break;
    }
    throw IoError(file.string() + ": cannot write this format (expected .vdb or .nrrd)");
}

} // namespace voxhap::volume
