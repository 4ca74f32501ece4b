// SPDX-License-Identifier: Apache-2.0
/// @file CmdFuse.cpp
/// @brief `voxhap fuse CT MR --out patient.vdb`: one patient's CT and MR in one
/// volume (fusion/PatientFusion.h), with its ITK transform file beside it.

#include "tools/Cli.h"
#include "tools/FusionReport.h"
#include "tools/LoadOptions.h"

#include "core/Format.h"
#include "fusion/PatientFusion.h"
#include "haptic/materials/MaterialField.h"

#include <nlohmann/json.hpp>

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

int run(const FuseOptions& o)
{
    if (volume::formatOf(o.out) != volume::VolumeFormat::Vdb) {
        throw UsageError("--out '" + o.out + "': expected a .vdb file name");
    }
    const bool bar = stderrIsTerminal() && !o.common.json;
    ReaderOptions ctReader = o.reader;
    ctReader.t1Map = ctReader.t1Weighted = false; // MR declarations are the MR's
    ctReader.series = o.ctSeries;
    ctReader.volume = 0;
    ReaderOptions mrReader = o.reader;
    mrReader.series = o.mrSeries;
    mrReader.volume = o.mrVolume;

    fusion::PatientFusionOptions fo;
    fo.ct = o.ct;
    fo.mr = o.mr;
    fo.ctLoad = loadOptions(ctReader, bar);
    fo.mrLoad = loadOptions(mrReader, bar);
    fo.registration.affine = o.affine;
    fo.start = o.start == "search" ? fusion::Start::Search
        : o.start == "geometry"    ? fusion::Start::Geometry
                                   : fusion::Start::Auto;
    fo.differentPatients = o.differentPatients;
    fo.table = &tissueTable(o.common);
    if (bar) {
        fo.registration.progress = [](double f, std::string_view step) {
            std::cerr << "\rregistering: " << step << " " << int(f * 100) << "%   " << std::flush;
        };
    }
    fusion::PatientFusion fused = [&] {
        try {
            fusion::PatientFusion f = fusion::fusePatient(fo);
            clearProgress();
            return f;
        } catch (...) {
            clearProgress();
            throw;
        }
    }();
    const std::filesystem::path tfm = fusion::writeFusion(fused, o.out);
    const volume::FusionRecord& record = *fused.volume.metadata().fusion;
    const segmentation::FusedLabelReport& labels = fused.labels;
    // Where the needle's damping will come from (physics.md §5.5): the same
    // material field simulate and plan build from this file.
    haptic::MaterialOptions mo;
    mo.needs.damping = true;
    const haptic::DampingSources sources =
        haptic::MaterialField(fused.volume, tissueTable(o.common), mo).dampingSources();

    if (o.common.json) {
        nlohmann::json j = volume::toJson(record);
        j["output"] = o.out;
        j["transform_file"] = tfm.string();
        j["resampled_voxels"] = fused.resample.activeVoxels;
        j["search_seconds"] = fused.registration.searchSeconds;
        j["registration_seconds"] = fused.registration.seconds;
        j["labels_changed_by_mr"] = labels.changed;
        j["soft_tissue_voxels_with_t1"] = labels.withT1;
        j["damping_from_t1_voxels"] = sources.fromT1Voxels;
        j["damping_from_table_voxels"] = sources.fromTableVoxels;
        j["damping_from_t1_fraction"] = sources.t1Fraction();
        std::cout << j.dump(2) << '\n';
        return 0;
    }
    std::cout << "CT   " << o.ct << (fused.ctSource.empty() ? "" : " (" + fused.ctSource + ")") << '\n';
    std::cout << "MR   " << o.mr << (fused.mrSource.empty() ? "" : " (" + fused.mrSource + ")") << '\n';
    printFusionRecord(std::cout, record, "  ");
    std::cout << "labels: " << labels.withT1 << " of " << labels.softTissueVoxels << " soft-tissue voxels have T1, "
              << labels.changed << " relabelled by it\n";
    std::cout << "damping: " << fixed(100.0 * sources.t1Fraction(), 1) << " % of the body from T1 (Eq. 4), "
              << fixed(100.0 * (1.0 - sources.t1Fraction()), 1) << " % from the tissue table by label\n";
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
    // --volume too: the loader's refusal of a 4D series names --volume, and
    // only the MR of a pair can be one.
    cmd->add_option("--mr-volume,--volume", o->mrVolume, "DICOM: which 3D volume of a 4D MR series, from 1")
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
    cmd->add_flag("--skip-bad", o->reader.skipBad,
        "DICOM: load a series without its unreadable files (each named on stderr), as the loader's refusal offers");
    cmd->add_option(
           "--memory-cap", o->reader.memoryCapMb, "Refuse inputs whose grid could exceed this many MiB (default 4096)")
        ->check(CLI::Range(1.0, 1e7));
    cmd->add_flag("--t1-map", o->reader.t1Map, "The MR's values are a T1 map in ms, whatever its headers say");
    cmd->add_flag("--t1-weighted", o->reader.t1Weighted, "Declare the MR T1-weighted (normalised per scan to T1)");
    addCommonOptions(*cmd, o->common);
    return [o] { return run(*o); };
}

} // namespace voxhap::tools
