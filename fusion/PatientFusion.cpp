// SPDX-License-Identifier: Apache-2.0
/// @file PatientFusion.cpp
/// @brief The composition, with the checks in the order a user meets them:
/// the inputs, the patient, then the registration's own refusals.

#include "fusion/PatientFusion.h"

#include "core/AtomicFile.h"
#include "core/Errors.h"
#include "core/Format.h"
#include "volume/dicom/DicomIdentity.h"

#include <chrono>

namespace voxhap::fusion {

namespace {

namespace fs = std::filesystem;

struct Loaded {
    volume::Volume volume;
    volume::DicomIdentity identity;
    std::string source; ///< "DICOM series #2, CT, 205 slices"; empty for other files
};

Loaded load(const fs::path& path, const volume::LoadOptions& options)
{
    volume::DicomLoadReport report;
    volume::Volume v = volume::loadVolume(path, options, &report);
    Loaded out{std::move(v), {}, {}};
    if (!report.series.files.empty()) {
        try {
            out.identity = volume::readDicomIdentity(report.series.files.front());
        } catch (const IoError&) {
            // The loader read this file: an identity it cannot parse is unknown, not a refusal.
        }
        out.source = "DICOM series #" + std::to_string(report.series.index) + ", " + report.series.modality + ", " +
            std::to_string(report.series.slices) + " slices" +
            (report.volume ? ", volume " + std::to_string(report.volume) : "");
    }
    return out;
}

} // namespace

PatientFusion fusePatient(const PatientFusionOptions& o)
{
    const auto t0 = std::chrono::steady_clock::now();
    const volume::TissueTable& table = o.table ? *o.table : volume::TissueTable::builtin();
    Loaded ct = load(o.ct, o.ctLoad);
    Loaded mr = load(o.mr, o.mrLoad);
    const double loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    registration::FusionOptions fo;
    fo.ctFile = o.ct.string();
    fo.mrFile = o.mr.string();
    fo.ctSource = ct.source;
    fo.mrSource = mr.source;
    fo.registration = o.registration;
    registration::checkFusionInputs(ct.volume, mr.volume, fo);
    if (!o.differentPatients) {
        registration::checkSamePatient(
            {ct.identity.patientId, ct.identity.patientName}, {mr.identity.patientId, mr.identity.patientName}, fo);
    }
    const bool sameFrame =
        !ct.identity.frameOfReferenceUid.empty() && ct.identity.frameOfReferenceUid == mr.identity.frameOfReferenceUid;
    fo.registration.start = o.start == Start::Geometry || (o.start == Start::Auto && sameFrame)
        ? registration::StartRule::Geometry
        : registration::StartRule::Search;

    registration::FusionResult fused = registration::fuse(ct.volume, mr.volume, fo);
    const volume::FieldStrength field = mr.volume.metadata().fieldStrength.value_or(volume::FieldStrength::T1_5);
    PatientFusion out{std::move(fused.volume), std::move(fused.registration), fused.resample, {},
        std::move(fused.transformText), ct.source, mr.source, loadSeconds};
    out.labels = segmentation::labelFused(out.volume, table, field);
    volume::FusionRecord& record = *out.volume.metadata().fusion;
    record.channelSources["label"] = "CT rules on hu; " +
        (out.labels.note.empty() ? "fat and muscle from the MR's T1 where it exists (split at " +
                    fixed(out.labels.thresholdMs, 0) + " ms)"
                                 : out.labels.note);
    record.mrPath = fs::absolute(o.mr).lexically_normal().string();
    record.mrSeries = o.mrLoad.dicom.series;
    record.mrVolume = std::int64_t(o.mrLoad.dicom.volume);
    return out;
}

fs::path writeFusion(const PatientFusion& f, const fs::path& vdb)
{
    fs::path tfm = vdb;
    tfm.replace_extension(".tfm");
    OutputSet outputs;
    outputs.add(vdb, [&](const fs::path& tmp) { volume::saveVolume(f.volume, tmp); });
    outputs.addStream(tfm, [&](std::ostream& os) { os << f.transformText; });
    outputs.commit();
    return tfm;
}

} // namespace voxhap::fusion
