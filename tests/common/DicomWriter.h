// SPDX-License-Identifier: Apache-2.0
/// @file DicomWriter.h
/// @brief Write small synthetic DICOM slices with GDCM, for reader tests.
///
/// The pixel values are a known function of (column, row, slice), so a test
/// can check every voxel the reader returns against the formula.
#pragma once

#include "core/Math.h"

#include <gdcmAttribute.h>
#include <gdcmImageWriter.h>
#include <gdcmReader.h>
#include <gdcmUIDs.h>
#include <gdcmWriter.h>

#include <cstdint>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace voxhap::test {

/// @brief One slice to write.
struct SyntheticSlice {
    std::string seriesUid = "1.2.826.0.1.3680043.2.1125.99.1";
    std::string modality = "CT";
    std::string seriesDescription = "synthetic";
    int rows = 12, columns = 16;
    Vec3d position{-20.0, -30.0, 0.0}; ///< centre of the first pixel [mm, LPS]
    Vec3d rowDirection{1, 0, 0};
    Vec3d columnDirection{0, 1, 0};
    double pixelSpacing[2] = {0.75, 0.5}; ///< between rows, between columns [mm]
    double slope = 1.0, intercept = -1024.0;
    double gantryTilt = 0.0;    ///< written to (0018,1120) [deg]
    double fieldStrength = 0.0; ///< written to (0018,0087) [T] if > 0
    /// MR sequence fields (written when not empty / > 0): what the weighting rule reads.
    std::string scanningSequence, sequenceVariant, sequenceName, imageType;
    double repetitionTimeMs = 0, echoTimeMs = 0, flipAngleDeg = 0;
    int echoNumber = 0;        ///< (0018,0086) if > 0
    int acquisitionNumber = 0; ///< (0020,0012) if > 0
    int instanceNumber = 0;    ///< (0020,0013) if > 0
    std::string seriesNumber;  ///< (0020,0011) if not empty
    /// The patient and frame of reference (written when not empty): what fusion checks.
    std::string patientId, patientName, frameOfReferenceUid;
    std::vector<std::int16_t> pixels; ///< rows × columns stored values, column fastest
};

/// @brief The image fields a single slice and a multi-frame file share: pixel format,
/// geometry of @p s with slice step @p step, rescale and the pixel data @p pixels.
inline void setImage(
    gdcm::Image& img, const SyntheticSlice& s, unsigned frames, double step, const std::vector<std::int16_t>& pixels)
{
    img.SetNumberOfDimensions(frames > 1 ? 3 : 2); // 3: GDCM writes Enhanced CT with per-frame groups
    img.SetDimension(0, unsigned(s.columns));
    img.SetDimension(1, unsigned(s.rows));
    if (frames > 1) img.SetDimension(2, frames);
    img.SetPixelFormat(gdcm::PixelFormat::INT16);
    img.SetPhotometricInterpretation(gdcm::PhotometricInterpretation::MONOCHROME2);
    img.SetTransferSyntax(gdcm::TransferSyntax::ExplicitVRLittleEndian);
    const double origin[3] = {s.position.x(), s.position.y(), s.position.z()};
    const double dircos[6] = {s.rowDirection.x(), s.rowDirection.y(), s.rowDirection.z(), s.columnDirection.x(),
        s.columnDirection.y(), s.columnDirection.z()};
    const double spacing[3] = {s.pixelSpacing[1], s.pixelSpacing[0], step}; // GDCM: x (between columns), y
    img.SetOrigin(origin);
    img.SetDirectionCosines(dircos);
    img.SetSpacing(spacing);
    img.SetSlope(s.slope);
    img.SetIntercept(s.intercept);
    gdcm::DataElement pixel(gdcm::Tag(0x7fe0, 0x0010));
    pixel.SetByteValue(reinterpret_cast<const char*>(pixels.data()), std::uint32_t(pixels.size() * 2));
    img.SetDataElement(pixel);
}

/// @brief SOP class @p sopClass, modality and series UID of @p s.
inline void setIdentity(gdcm::DataSet& ds, const SyntheticSlice& s, gdcm::UIDs::TSName sopClass)
{
    gdcm::Attribute<0x0008, 0x0016> sop;
    sop.SetValue(gdcm::UIDs::GetUIDString(sopClass));
    ds.Replace(sop.GetAsDataElement());
    gdcm::Attribute<0x0008, 0x0060> modality;
    modality.SetValue(s.modality);
    ds.Replace(modality.GetAsDataElement());
    gdcm::Attribute<0x0020, 0x000e> uid;
    uid.SetValue(s.seriesUid);
    ds.Replace(uid.GetAsDataElement());
}

/// @brief Read @p file, let @p edit change it, write it back.
template <typename Edit> void rewrite(const std::filesystem::path& file, Edit&& edit)
{
    gdcm::Reader r;
    r.SetFileName(file.string().c_str());
    if (!r.Read()) throw std::runtime_error("GDCM could not read back " + file.string());
    edit(r.GetFile());
    gdcm::Writer w;
    w.SetFile(r.GetFile());
    w.SetFileName(file.string().c_str());
    if (!w.Write()) throw std::runtime_error("GDCM could not rewrite " + file.string());
}

/// @brief Write @p s as a CT or MR Image Storage file (explicit VR little endian).
inline void writeSyntheticSlice(const SyntheticSlice& s, const std::filesystem::path& file)
{
    gdcm::ImageWriter w;
    setImage(w.GetImage(), s, 1, 1.0, s.pixels);
    gdcm::DataSet& ds = w.GetFile().GetDataSet();
    setIdentity(ds, s, s.modality == "MR" ? gdcm::UIDs::MRImageStorage : gdcm::UIDs::CTImageStorage);
    gdcm::Attribute<0x0008, 0x103e> description;
    description.SetValue(s.seriesDescription);
    ds.Replace(description.GetAsDataElement());
    gdcm::Attribute<0x0018, 0x1120> tilt;
    tilt.SetValue(s.gantryTilt);
    ds.Replace(tilt.GetAsDataElement());
    if (s.fieldStrength > 0) {
        gdcm::Attribute<0x0018, 0x0087> field;
        field.SetValue(s.fieldStrength);
        ds.Replace(field.GetAsDataElement());
    }
    // Strings and numbers as decimal strings, each only when given.
    const auto text = [&ds](std::uint16_t g, std::uint16_t e, const gdcm::VR& vr, const std::string& v) {
        if (v.empty()) return;
        std::string padded = v;
        if (padded.size() % 2) padded += ' ';
        gdcm::DataElement de(gdcm::Tag(g, e));
        de.SetVR(vr);
        de.SetByteValue(padded.data(), std::uint32_t(padded.size()));
        ds.Replace(de);
    };
    const auto number = [&](std::uint16_t g, std::uint16_t e, const gdcm::VR& vr, double v) {
        if (v <= 0) return;
        std::ostringstream os;
        os << v;
        text(g, e, vr, os.str());
    };
    text(0x0018, 0x0020, gdcm::VR::CS, s.scanningSequence);
    text(0x0018, 0x0021, gdcm::VR::CS, s.sequenceVariant);
    text(0x0018, 0x0024, gdcm::VR::SH, s.sequenceName);
    text(0x0008, 0x0008, gdcm::VR::CS, s.imageType);
    text(0x0020, 0x0011, gdcm::VR::IS, s.seriesNumber);
    text(0x0010, 0x0020, gdcm::VR::LO, s.patientId);
    text(0x0010, 0x0010, gdcm::VR::PN, s.patientName);
    text(0x0020, 0x0052, gdcm::VR::UI, s.frameOfReferenceUid);
    number(0x0018, 0x0080, gdcm::VR::DS, s.repetitionTimeMs);
    number(0x0018, 0x0081, gdcm::VR::DS, s.echoTimeMs);
    number(0x0018, 0x1314, gdcm::VR::DS, s.flipAngleDeg);
    number(0x0018, 0x0086, gdcm::VR::IS, s.echoNumber);
    number(0x0020, 0x0012, gdcm::VR::IS, s.acquisitionNumber);
    number(0x0020, 0x0013, gdcm::VR::IS, s.instanceNumber);

    w.SetFileName(file.string().c_str());
    if (!w.Write()) throw std::runtime_error("GDCM could not write " + file.string());

    // GDCM writes a 2D image's ImagePositionPatient with z = 0: put the true
    // position back with a plain reader/writer pass.
    rewrite(file, [&](gdcm::File& f) {
        gdcm::Attribute<0x0020, 0x0032> ipp = {{s.position.x(), s.position.y(), s.position.z()}};
        f.GetDataSet().Replace(ipp.GetAsDataElement());
    });
}

/// @brief Rewrite @p file declaring transfer syntax @p ts while its data
/// stays plain little-endian: a header that contradicts its pixel data.
inline void relabelTransferSyntax(const std::filesystem::path& file, gdcm::TransferSyntax::TSType ts)
{
    rewrite(file, [&](gdcm::File& f) { f.GetHeader().SetDataSetTransferSyntax(gdcm::TransferSyntax(ts)); });
}

/// @brief Write @p frames (one slice each, same grid, positions along the
/// normal with step @p step) as one multi-frame (enhanced) CT file.
inline void writeSyntheticMultiFrame(
    const std::vector<SyntheticSlice>& frames, double step, const std::filesystem::path& file)
{
    const SyntheticSlice& s = frames.front();
    std::vector<std::int16_t> all;
    for (const auto& f : frames) all.insert(all.end(), f.pixels.begin(), f.pixels.end());
    gdcm::ImageWriter w;
    setImage(w.GetImage(), s, unsigned(frames.size()), step, all);
    setIdentity(w.GetFile().GetDataSet(), s, gdcm::UIDs::EnhancedCTImageStorage);
    w.SetFileName(file.string().c_str());
    if (!w.Write()) throw std::runtime_error("GDCM could not write " + file.string());
}

} // namespace voxhap::test
