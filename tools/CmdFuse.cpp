// SPDX-License-Identifier: Apache-2.0
/// @file CmdFuse.cpp
/// @brief `voxhap fuse CT MR --out patient.vdb`: one patient's CT and MR in one
/// volume (registration/Fusion.h, segmentation/FusedLabels.h), with its ITK
/// transform file beside it.

#include "tools/Cli.h"
#include "tools/FusionReport.h"
#include "tools/LoadOptions.h"

#include "core/AtomicFile.h"
#include "core/Format.h"
#include "registration/Fusion.h"
#include "segmentation/FusedLabels.h"
#include "volume/VolumeFile.h"
#include "volume/dicom/DicomIdentity.h"

#include <nlohmann/json.hpp>

#include <fstream>
#include <iostream>
#include <memory>

namespace voxhap::tools {

namespace {

struct FuseOptions {
    CommonOptions common;
    ReaderOptions reader;
    std::string ct, mr, out;
    std::string ctSeries, mrSeries;
    std::size_t mrVolume = 0;
    bool affine = false;
    bool differentPatients = false;
    std::string start = "auto";
};

/// One input loaded, with what its DICOM headers say of the patient and frame.
struct Input {
    volume::Volume volume;
    volume::DicomLoadReport report;
    volume::DicomIdentity identity;
    std::string source; ///< "DICOM series #2 (CT, 205 slices)"; empty for files
};

Input load(const std::string& path, ReaderOptions opts, const std::string& series, std::size_t volumeIndex, bool bar)
{
    opts.series = series;
    opts.volume = volumeIndex;
    volume::DicomLoadReport report;
    volume::Volume v = loadVolumeWithProgress(path, opts, bar, &report);
    Input in{std::move(v), report, {}, {}};
    if (!report.series.files.empty()) {
        try {
            in.identity = volume::readDicomIdentity(report.series.files.front());
        } catch (const IoError&) {
            // The loader read the file; an identity it cannot parse is unknown, not a refusal.
        }
        in.source = "DICOM series #" + std::to_string(report.series.index) + ", " + report.series.modality + ", " +
            std::to_string(report.series.slices) + " slices" +
            (report.volume ? ", volume " + std::to_string(report.volume) : "");
    }
    return in;
}

int run(const FuseOptions& o)
{
    if (volume::formatOf(o.out) != volume::VolumeFormat::Vdb) {
        throw UsageError("--out '" + o.out + "': expected a .vdb file name");
    }
    const bool bar = stderrIsTerminal() && !o.common.json;
    ReaderOptions mrReader = o.reader;
    ReaderOptions ctReader = o.reader;
    ctReader.t1Map = ctReader.t1Weighted = false; // MR declarations are the MR's
    Input ct = load(o.ct, ctReader, o.ctSeries, 0, bar);
    Input mr = load(o.mr, mrReader, o.mrSeries, o.mrVolume, bar);

    registration::FusionOptions fo;
    fo.ctFile = o.ct;
    fo.mrFile = o.mr;
    fo.ctSource = ct.source;
    fo.mrSource = mr.source;
    fo.registration.affine = o.affine;
    if (!o.differentPatients) {
        registration::checkSamePatient(
            {ct.identity.patientId, ct.identity.patientName}, {mr.identity.patientId, mr.identity.patientName}, fo);
    }
    const bool sameFrame =
        !ct.identity.frameOfReferenceUid.empty() && ct.identity.frameOfReferenceUid == mr.identity.frameOfReferenceUid;
    fo.registration.start = o.start == "geometry" || (o.start == "auto" && sameFrame)
        ? registration::StartRule::Geometry
        : registration::StartRule::Search;
    if (bar) {
        fo.registration.progress = [](double f, std::string_view step) {
            std::cerr << "\rregistering: " << step << " " << int(f * 100) << "%   " << std::flush;
        };
    }
    registration::FusionResult fused = registration::fuse(ct.volume, mr.volume, fo);
    if (bar) std::cerr << "\r\033[K" << std::flush;
    ct.volume = volume::Volume(volume::Geometry{}, volume::IndexBox{}); // the inputs' memory back
    mr.volume = volume::Volume(volume::Geometry{}, volume::IndexBox{});

    const auto& table = tissueTable(o.common);
    const volume::FieldStrength field = volume::FieldStrength::T1_5; // PLACEHOLDER until the typed field strength lands
    const segmentation::FusedLabelReport labels = segmentation::labelFused(fused.volume, table, field);
    auto& record = *fused.volume.metadata().fusion;
    record.mrPath = std::filesystem::absolute(o.mr).lexically_normal().string();
    record.mrSeries = o.mrSeries;
    record.mrVolume = std::int64_t(o.mrVolume);
    record.channelSources["label"] = "CT rules on hu; " +
        (labels.note.empty()
                ? "fat and muscle from the MR's T1 where it exists (split at " + fixed(labels.thresholdMs, 0) + " ms)"
                : labels.note);

    std::filesystem::path tfm = o.out;
    tfm.replace_extension(".tfm");
    OutputSet outputs;
    outputs.add(o.out, [&](const std::filesystem::path& tmp) { volume::saveVolume(fused.volume, tmp); });
    outputs.addStream(tfm, [&](std::ostream& os) { os << fused.transformText; });
    outputs.commit();

    if (o.common.json) {
        nlohmann::json j = volume::toJson(record);
        j["output"] = o.out;
        j["transform_file"] = tfm.string();
        j["resampled_voxels"] = fused.resample.activeVoxels;
        j["search_seconds"] = fused.registration.searchSeconds;
        j["registration_seconds"] = fused.registration.seconds;
        j["labels_changed_by_mr"] = labels.changed;
        j["soft_tissue_voxels_with_t1"] = labels.withT1;
        std::cout << j.dump(2) << '\n';
        return 0;
    }
    std::cout << "CT   " << o.ct << (ct.source.empty() ? "" : " (" + ct.source + ")") << '\n';
    std::cout << "MR   " << o.mr << (mr.source.empty() ? "" : " (" + mr.source + ")") << '\n';
    printFusionRecord(std::cout, record, "  ");
    std::cout << "labels: " << labels.withT1 << " of " << labels.softTissueVoxels << " soft-tissue voxels have T1, "
              << labels.changed << " relabelled by it\n";
    std::cout << "time: registration " << fixed(fused.registration.seconds, 2) << " s (orientation search "
              << fixed(fused.registration.searchSeconds, 2) << " s), resampling " << fixed(fused.resample.seconds, 2)
              << " s\n";
    std::cout << "wrote " << o.out << "\n      " << tfm.string()
              << " (ITK transform: load it in 3D Slicer and apply it to the MR)\n";
    return 0;
}

} // namespace

Action registerFuse(CLI::App& app)
{
    auto o = std::make_shared<FuseOptions>();
    CLI::App* cmd = app.add_subcommand("fuse",
        "Register a patient's MR onto their CT and write one volume on the CT's grid: hu from the CT, the MR as t1 "
        "(a T1 map or a normalised T1-weighted scan) or intensity, labels from both; and the transform as an ITK "
        ".tfm beside it");
    cmd->add_option("ct", o->ct, "The CT: a DICOM directory or file, .nii/.nii.gz, .nrrd, .mha/.mhd or .vdb")
        ->required();
    cmd->add_option("mr", o->mr, "The MR of the same patient, in any of those formats")->required();
    cmd->add_option("--out", o->out, "The fused volume (.vdb); the transform goes beside it as .tfm")->required();
    cmd->add_option("--ct-series", o->ctSeries, "DICOM: the CT's series (UID, SeriesNumber or #N, as for --series)");
    cmd->add_option("--mr-series", o->mrSeries, "DICOM: the MR's series");
    cmd->add_option("--mr-volume", o->mrVolume, "DICOM: which 3D volume of a 4D MR series, from 1")
        ->check(CLI::Range(std::size_t(1), std::size_t(1000000)));
    cmd->add_flag("--affine", o->affine, "Add an affine stage after the rigid one (scanner scale and shear)");
    cmd->add_flag("--different-patients", o->differentPatients,
        "Fuse series whose PatientID or PatientName differ. Dangerous: another person's MR gives the needle "
        "another person's tissue, and nothing in the result shows it");
    cmd->add_option("--start", o->start,
           "How the optimiser starts: auto (the header geometry when both DICOM series share a "
           "FrameOfReferenceUID, else the search), search (the best of 24 axis-aligned turns by the metric: "
           "head first against feet first), geometry (the header geometry as it is)")
        ->check(CLI::IsMember({"auto", "search", "geometry"}));
    cmd->add_flag("--resample", o->reader.resample, "DICOM: resample uneven, gapped or tilted slice stacks");
    cmd->add_option(
           "--memory-cap", o->reader.memoryCapMb, "Refuse inputs whose grid could exceed this many MiB (default 4096)")
        ->check(CLI::Range(1.0, 1e7));
    cmd->add_flag("--t1-map", o->reader.t1Map, "The MR's values are a T1 map in ms, whatever its headers say");
    cmd->add_flag("--t1-weighted", o->reader.t1Weighted, "Declare the MR T1-weighted (normalised per scan to T1)");
    addCommonOptions(*cmd, o->common);
    return [o] { return run(*o); };
}

} // namespace voxhap::tools
