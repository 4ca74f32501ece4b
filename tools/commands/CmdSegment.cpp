// SPDX-License-Identifier: Apache-2.0
/// @file CmdSegment.cpp
/// @brief `voxhap segment <in> --out seg.vdb [--labels map.json] [--export labels.nrrd]`:
/// tissue labels, imported label maps and critical-structure distance fields,
/// with a per-label summary.

#include "tools/Cli.h"
#include "tools/LoadOptions.h"

#include "core/AtomicFile.h"
#include "core/Errors.h"
#include "segmentation/DistanceField.h"
#include "segmentation/Segmentation.h"
#include "segmentation/TotalSegmentator.h"
#include "volume/Grids.h"
#include "volume/VolumeFile.h"

#include <nlohmann/json.hpp>

#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

namespace voxhap::tools {

namespace {

struct SegmentCliOptions {
    CommonOptions common;
    ReaderOptions reader;
    std::string in, out, labels, labelMap, exportNrrd, critical;
    double bandMm = 30.0;
    bool noAuto = false;
};

std::vector<std::string> splitList(const std::string& s)
{
    std::vector<std::string> out;
    std::stringstream in(s);
    for (std::string item; std::getline(in, item, ',');) {
        if (!item.empty()) out.push_back(item);
    }
    return out;
}

/// A volume holding only @p v's label grid (shared, not copied), for --export.
volume::Volume labelsOnly(const volume::Volume& v)
{
    volume::Volume out(v.transformPtr()->copy(), v.indexBox());
    out.metadata() = v.metadata();
    out.setGrid(
        volume::Channel::Label, std::const_pointer_cast<openvdb::GridBase>(v.grid(volume::Channel::Label))->copyGrid());
    return out;
}

int run(const SegmentCliOptions& o)
{
    const auto outFormat = volume::formatOf(o.out);
    if (outFormat != volume::VolumeFormat::Vdb) throw UsageError("--out '" + o.out + "': expected a .vdb file name");
    if (!o.exportNrrd.empty() && volume::formatOf(o.exportNrrd) != volume::VolumeFormat::Nrrd) {
        throw UsageError("--export '" + o.exportNrrd + "': expected a .nrrd file name");
    }
    if (!o.labelMap.empty() && o.labels.empty())
        throw UsageError("--label-map needs --labels (the mapping of its values to tissues)");
    const volume::TissueTable& table = tissueTable(o.common);
    const bool terminal = stderrIsTerminal() && !o.common.json;

    segmentation::SegmentOptions so;
    so.automatic = !o.noAuto;
    so.critical = splitList(o.critical);
    for (const auto& name : so.critical) table.at(name); // unknown names fail before the long work
    so.distanceBandMm = o.bandMm;
    // The cap covers the work too: the volume's grids plus segmentation's estimate.
    so.memoryCapBytes = std::uint64_t(o.reader.memoryCapMb * double(1 << 20));
    if (terminal) so.progress = [](double, std::string_view step) { std::cerr << "segment: " << step << "...\n"; };

    std::unique_ptr<volume::Volume> imported;
    if (!o.labels.empty()) {
        segmentation::ImportedLabels il;
        std::string mapFile;
        if (o.labels == "totalsegmentator") {
            // TotalSegmentator's multilabel file or its folder of per-class masks.
            if (o.labelMap.empty())
                throw UsageError("--labels totalsegmentator needs --label-map: TotalSegmentator's multilabel .nii.gz "
                                 "or its folder of per-class masks");
            mapFile = o.labelMap;
            il.mapping = segmentation::totalSegmentatorMapping(table);
            imported = std::make_unique<volume::Volume>(segmentation::loadTotalSegmentator(mapFile, table));
        } else {
            il.mapping = segmentation::loadLabelMapping(o.labels, table);
            mapFile = o.labelMap.empty() ? il.mapping.file.string() : o.labelMap;
            if (mapFile.empty())
                throw UsageError(o.labels + ": file: no label map named here; give one with --label-map");
            ReaderOptions plain; // label values are not HU: keep every voxel, whatever its value
            plain.airHu = -1e30;
            imported = std::make_unique<volume::Volume>(loadVolumeWithProgress(mapFile, plain, terminal));
        }
        il.labels = imported.get();
        il.file = mapFile;
        so.imported = std::move(il);
    }

    volume::Volume v = loadVolumeWithProgress(o.in, o.reader, terminal);
    const segmentation::SegmentReport r = segmentation::segment(v, table, so);
    // The segmented volume and its --export replace an earlier run's together: a kill
    // between the two can leave one missing, never a new .vdb beside a stale export.
    OutputSet outputs;
    outputs.add(o.out, [&v](const std::filesystem::path& tmp) { volume::saveVolume(v, tmp); });
    if (!o.exportNrrd.empty())
        outputs.add(o.exportNrrd, [&v](const std::filesystem::path& tmp) { volume::saveVolume(labelsOnly(v), tmp); });
    outputs.commit();

    if (o.common.json) {
        nlohmann::json j;
        j["input"] = o.in;
        j["output"] = o.out;
        if (!o.exportNrrd.empty()) j["export"] = o.exportNrrd;
        j["method"] = r.method;
        j["seconds"] = r.seconds;
        j["memory_mib"] = {{"input", double(r.inputBytes) / double(1 << 20)},
            {"working_estimate", double(r.workingBytes) / double(1 << 20)}, {"cap", o.reader.memoryCapMb}};
        j["imported_voxels"] = r.importedVoxels;
        j["distance_fields"] = r.distanceFields;
        j["distance_band_mm"] = o.bandMm;
        j["notes"] = r.notes;
        j["body_width_mm"] = r.bodyWidthMm;
        j["torso_fraction"] = r.torsoFraction;
        j["labels"] = nlohmann::json::array();
        for (const auto& l : r.labels) {
            j["labels"].push_back({{"id", l.id}, {"name", l.name}, {"voxels", l.voxels}, {"ml", l.ml},
                {"min_mm", {l.bounds[0].x(), l.bounds[0].y(), l.bounds[0].z()}},
                {"max_mm", {l.bounds[1].x(), l.bounds[1].y(), l.bounds[1].z()}}});
        }
        std::cout << j.dump(2) << '\n';
        return 0;
    }
    std::cout << "segmented " << o.in << " (" << r.method << ") in " << std::fixed << std::setprecision(1) << r.seconds
              << " s";
    if (r.importedVoxels) std::cout << "; " << r.importedVoxels << " voxels from the imported map";
    std::cout << "\n";
    // What the rules could not do here (a head, a limb, an MR contrast): said, not hidden.
    for (const auto& note : r.notes) std::cout << "note: " << note << '\n';
    std::cout << '\n';
    std::cout << std::left << std::setw(4) << "id" << std::setw(22) << "label" << std::right << std::setw(11)
              << "voxels" << std::setw(10) << "ml"
              << "   bounding box [mm, LPS]\n";
    for (const auto& l : r.labels) {
        std::cout << std::left << std::setw(4) << l.id << std::setw(22) << l.name << std::right << std::setw(11)
                  << l.voxels << std::setw(10) << std::setprecision(1) << l.ml << "   (" << std::setprecision(0)
                  << l.bounds[0].x() << ", " << l.bounds[0].y() << ", " << l.bounds[0].z() << ") .. ("
                  << l.bounds[1].x() << ", " << l.bounds[1].y() << ", " << l.bounds[1].z() << ")\n";
    }
    std::cout << "\ndistance fields:";
    for (const auto& d : r.distanceFields) std::cout << ' ' << d;
    std::cout << (r.distanceFields.empty() ? " none (no critical tissue found)\n" : "\n");
    std::cout << "wrote " << o.out;
    if (!o.exportNrrd.empty()) std::cout << " and " << o.exportNrrd;
    std::cout << "\n";
    return 0;
}

} // namespace

Action registerSegment(CLI::App& app)
{
    auto o = std::make_shared<SegmentCliOptions>();
    CLI::App* cmd = app.add_subcommand("segment",
        "Label tissues (CT: HU thresholds, connectivity and shape rules; MR: fat and muscle from T1), apply an "
        "imported label map, and compute signed distance fields of the critical structures (sdf.<tissue> grids)");
    cmd->add_option("in", o->in, "Input volume: a DICOM directory or file, .nii/.nii.gz, .nrrd, .mha/.mhd or .vdb")
        ->required();
    cmd->add_option("--out", o->out, "Output .vdb: the input grids, the label grid and the distance fields")
        ->required();
    cmd->add_option("--labels", o->labels,
        "Label mapping JSON {\"schema\": \"voxhap.label-mapping/1\", \"file\": MAP, \"labels\": {VALUE: "
        "TISSUE}}: the imported labels override the automatic ones; or 'totalsegmentator': the built-in mapping of "
        "TotalSegmentator v2's 117 'total' classes, with --label-map its multilabel file or folder of masks");
    cmd->add_option("--label-map", o->labelMap,
        "The label map (.nrrd, .nii, .mha, .vdb) if the mapping does not name it; with --labels totalsegmentator a "
        "multilabel file or a folder of <class>.nii.gz masks");
    cmd->add_option(
        "--export", o->exportNrrd, "Also write the label grid alone as .nrrd (opens in 3D Slicer as a label map)");
    cmd->add_option("--critical", o->critical,
        "Comma-separated tissues that get a distance field (default: those the tissue table marks critical)");
    cmd->add_option("--band", o->bandMm, "Distance fields are exact within this distance of a structure [mm]")
        ->check(CLI::PositiveNumber)
        ->default_val(30.0);
    cmd->add_flag("--no-auto", o->noAuto, "No automatic labels: only the imported map (and the input's own labels)");
    addReaderOptions(*cmd, o->reader);
    addCommonOptions(*cmd, o->common);
    return [o] { return run(*o); };
}

} // namespace voxhap::tools
