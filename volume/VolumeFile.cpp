// SPDX-License-Identifier: Apache-2.0
/// @file VolumeFile.cpp
/// @brief Format dispatch for loading and saving volumes.

#include "volume/VolumeFile.h"

#include "volume/Errors.h"
#include "volume/MetaImageFile.h"
#include "volume/NiftiFile.h"
#include "volume/NrrdFile.h"
#include "volume/VdbFile.h"

#include <algorithm>
#include <cctype>

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
    case VolumeFormat::Dicom: return "dicom";
    case VolumeFormat::Vdb: return "vdb";
    case VolumeFormat::Nrrd: return "nrrd";
    case VolumeFormat::Nifti: return "nifti";
    case VolumeFormat::MetaImage: return "metaimage";
    case VolumeFormat::Unknown: break;
    }
    return "unknown";
}

RasterOptions rasterOptions(const LoadOptions& o)
{
    RasterOptions r;
    r.channel = o.channel;
    r.airHu = o.dicom.airHu;
    r.airT1 = o.dicom.airT1;
    r.memoryCapBytes = o.dicom.memoryCapBytes;
    r.progress = o.dicom.progress;
    return r;
}

Volume loadVolume(const std::filesystem::path& path, const LoadOptions& options, DicomLoadReport* report)
{
    if (!std::filesystem::exists(path)) throw IoError(path.string() + ": no such file or directory");
    switch (formatOf(path)) {
    case VolumeFormat::Dicom: return loadDicom({path}, options.dicom, report);
    case VolumeFormat::Vdb: return loadVdb(path);
    case VolumeFormat::Nrrd: return loadNrrd(path, rasterOptions(options));
    case VolumeFormat::Nifti: return loadNifti(path, rasterOptions(options));
    case VolumeFormat::MetaImage: return loadMetaImage(path, rasterOptions(options));
    case VolumeFormat::Unknown: break;
    }
    throw IoError(path.string() + ": unknown format (expected a DICOM directory or file, .nii, .nii.gz, .nrrd, .mha, .mhd or .vdb)");
}

void saveVolume(const Volume& v, const std::filesystem::path& file)
{
    switch (formatOf(file)) {
    case VolumeFormat::Vdb: saveVdb(v, file); return;
    case VolumeFormat::Nrrd: {
        const Channel c = v.has(Channel::Hu) ? Channel::Hu : v.has(Channel::T1) ? Channel::T1 : Channel::Label;
        try {
            saveNrrd(v, c, file);
        } catch (const ValueError& e) {
            throw IoError(e.what());
        }
        return;
    }
    default: break;
    }
    throw IoError(file.string() + ": cannot write this format (expected .vdb or .nrrd)");
}

} // namespace voxhap::volume
