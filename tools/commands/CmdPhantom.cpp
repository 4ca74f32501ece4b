// SPDX-License-Identifier: Apache-2.0
/// @file CmdPhantom.cpp
/// @brief `voxhap phantom <kind>`: generate a synthetic volume and save it as .vdb.

#include "tools/Cli.h"
#include "tools/InfoReport.h"

#include "core/AtomicFile.h"
#include "phantoms/PhantomScans.h"
#include "phantoms/Phantoms.h"
#include "volume/io/NrrdFile.h"
#include "volume/io/VdbFile.h"
#include "volume/mr/MrWeighting.h"

#include <nlohmann/json.hpp>

#include <filesystem>

#include <iostream>
#include <memory>
#include <sstream>

namespace voxhap::tools {

namespace {

struct PhantomOptions {
    CommonOptions common;
    std::string kind;
    std::string out;
    std::string spacing = "0.5";
    std::string rotate = "0,0,0";
    std::string field = "1.5";
    // lumbar
    std::string preset = "average";
    double bmi = 0;
    // slab
    std::string layers;
    double tilt = 0;
    // sphere
    std::string slabTissue = "fat", sphereTissue = "muscle";
    double radius = 10, thickness = 40;
    // torso
    double lesionRadius = 8;
    // a CT and MR scan pair instead of one volume
    std::string scanPair;
    std::string mrTurn = "0,0,0", mrShift = "0,0,0", mrSpacing = "1,1,4";
    double mrNoise = 0.05;
    std::uint64_t seed = 1;
};

/// `--scan-pair DIR`: the phantom as a CT and an MR of it, each as a scanner
/// would export it (phantoms/PhantomScans.h), for trying `voxhap fuse`
/// against a known answer: DIR/ct.nrrd (hu), DIR/mr.nrrd with its BIDS sidecar
/// (a T1 map at --field), and DIR/truth.txt, the true MR-from-CT map as a 4×4
/// LPS matrix.
int writeScanPair(const PhantomOptions& o, const volume::PhantomModel& model, const volume::GridSpec& grid,
    const volume::TissueTable& table)
{
    namespace fs = std::filesystem;
    volume::PhantomMrScan scan;
    scan.rotation = rotationFromDegrees(parseVec3(o.mrTurn, "--mr-turn"));
    scan.translationMm = parseVec3(o.mrShift, "--mr-shift");
    scan.spacing = parseSpacing(o.mrSpacing, "--mr-spacing");
    scan.noiseOfMuscleT1 = o.mrNoise;
    scan.seed = o.seed;
    scan.field = grid.field;
    volume::PhantomScanTruth truth;
    const fs::path dir = o.scanPair;
    fs::create_directories(dir);
    const volume::Volume ct = volume::phantomCtScan(model, grid, table);
    const volume::Volume mr = volume::phantomMrScan(model, table, scan, &truth);
    OutputSet outputs;
    outputs.add(dir / "ct.nrrd",
        [&](const fs::path& tmp) { volume::saveNrrd(ct, volume::Channel::Hu, tmp, volume::NrrdEncoding::Gzip); });
    outputs.add(dir / "mr.nrrd", [&](const fs::path& tmp) {
        volume::saveNrrd(mr, volume::Channel::T1, tmp, volume::NrrdEncoding::Gzip, volume::NrrdKeys::Plain);
    });
    outputs.addStream(volume::bidsSidecarPath(dir / "mr.nrrd"),
        [&](std::ostream& os) { os << volume::phantomMrSidecar(scan.field); });
    outputs.addStream(dir / "truth.txt", [&](std::ostream& os) {
        os.precision(17);
        for (int r = 0; r < 3; ++r)
            os << truth.linear(r, 0) << ' ' << truth.linear(r, 1) << ' ' << truth.linear(r, 2) << ' ' << truth.offset[r]
               << '\n';
        os << "0 0 0 1\n";
    });
    outputs.commit();
    if (o.common.json) {
        nlohmann::json j;
        j["ct"] = (dir / "ct.nrrd").string();
        j["mr"] = (dir / "mr.nrrd").string();
        j["truth"] = (dir / "truth.txt").string();
        std::cout << j.dump(2) << '\n';
    } else {
        std::cout << "wrote " << (dir / "ct.nrrd").string() << " (CT, hu), " << (dir / "mr.nrrd").string()
                  << " (MR T1 map with its BIDS sidecar) and " << (dir / "truth.txt").string()
                  << " (the true MR-from-CT map)\n";
    }
    return 0;
}

std::vector<volume::SlabLayer> parseLayers(const std::string& text)
{
    std::vector<volume::SlabLayer> layers;
    std::istringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
        const auto colon = item.find(':');
        if (colon == std::string::npos)
            throw UsageError("--layers: expected tissue:mm[,tissue:mm...], got '" + item + "'");
        volume::SlabLayer layer;
        layer.tissue = item.substr(0, colon);
        try {
            std::size_t used = 0;
            layer.thicknessMm = std::stod(item.substr(colon + 1), &used);
            if (used != item.size() - colon - 1) throw std::invalid_argument("trailing text");
        } catch (const std::exception&) {
            throw UsageError("--layers: thickness of '" + layer.tissue + "' is not a number");
        }
        layers.push_back(layer);
    }
    if (layers.empty()) throw UsageError("--layers: no layers given");
    return layers;
}

int run(const PhantomOptions& o, const CLI::App& cmd)
{
    // Options that belong to another kind are mistakes, not silently ignored.
    const std::map<std::string, std::vector<std::string>> kOwn{
        {"lumbar", {"--preset", "--bmi"}},
        {"slab", {"--layers", "--tilt"}},
        {"sphere", {"--radius", "--thickness", "--slab-tissue", "--sphere-tissue"}},
        {"torso", {"--lesion-radius"}},
    };
    for (const auto& [kind, names] : kOwn) {
        if (kind == o.kind) continue;
        for (const auto& name : names) {
            if (cmd.count(name) > 0) throw UsageError(name + " does not apply to the " + o.kind + " phantom");
        }
    }

    const volume::TissueTable& table = tissueTable(o.common);
    volume::GridSpec grid;
    grid.spacing = parseSpacing(o.spacing, "--spacing");
    grid.direction = rotationFromDegrees(parseVec3(o.rotate, "--rotate"));
    if (o.field == "1.5" || o.field == "1.5T")
        grid.field = volume::FieldStrength::T1_5;
    else if (o.field == "3" || o.field == "3T")
        grid.field = volume::FieldStrength::T3;
    else
        throw UsageError("--field: expected 1.5 or 3, got '" + o.field + "'");

    volume::PhantomSpec spec;
    spec.kind = o.kind;
    if (!o.layers.empty()) spec.slab.layers = parseLayers(o.layers);
    spec.slab.tiltDeg = o.tilt;
    spec.sphere.slabTissue = o.slabTissue;
    spec.sphere.sphereTissue = o.sphereTissue;
    spec.sphere.radiusMm = o.radius;
    spec.sphere.slabThicknessMm = o.thickness;
    spec.lumbar.preset = volume::parseLumbarPreset(o.preset);
    if (cmd.count("--bmi") > 0) spec.lumbar.bmi = o.bmi;
    spec.torso.lesionRadiusMm = o.lesionRadius;
    const volume::PhantomModel model = volume::phantomModel(spec, table);
    if (!o.scanPair.empty()) return writeScanPair(o, model, grid, table);

    const std::string out = o.out.empty() ? o.kind + ".vdb" : o.out;
    if (stderrIsTerminal() && !o.common.json)
        std::cerr << "voxhap: generating the " << o.kind << " phantom...\r" << std::flush;
    const volume::Volume v = volume::makePhantom(model, grid, table);
    volume::saveVdb(v, out);
    const auto info = volume::describe(v, table);
    if (o.common.json) {
        std::cout << infoJson(info, out).dump(2) << '\n';
    } else {
        std::cout << "wrote " << out << "\n\n";
        printInfo(std::cout, info, out);
    }
    return 0;
}

} // namespace

Action registerPhantom(CLI::App& app)
{
    auto o = std::make_shared<PhantomOptions>();
    CLI::App* cmd = app.add_subcommand("phantom", "Generate a synthetic volume (hu, t1, label) and save it as .vdb");
    cmd->footer(
        "Kinds:\n"
        "  slab    layered slab stack (physics.md §7 R1); --layers, --tilt\n"
        "  sphere  sphere in a slab (physics.md §7 R5); --radius, --thickness, --slab-tissue, --sphere-tissue\n"
        "  lumbar  lumbar epidural: skin, fat, ligaments, flavum, epidural space, dura, CSF, two vertebrae;\n"
        "          --preset average|overweight|calcified ([S19] Table I), --bmi (SED = 2.52 + 0.11 BMI cm)\n"
        "  torso   spine-biopsy torso: vertebral body with lesion, lung bases, kidneys, aorta; --lesion-radius\n"
        "The skin surface is at y = 0 (LPS, mm) and the needle path runs along -y. The layers along\n"
        "the reference path are stored in the file and printed by `voxhap info`.");
    cmd->add_option("kind", o->kind, "slab, sphere, lumbar or torso")
        ->required()
        ->check(CLI::IsMember({"slab", "sphere", "lumbar", "torso"}));
    cmd->add_option("--out,-o", o->out, "Output .vdb file (default: <kind>.vdb)");
    cmd->add_option("--spacing", o->spacing, "Voxel size in mm: s or sx,sy,sz (default 0.5)");
    cmd->add_option("--rotate", o->rotate, "Grid orientation: rotations about x,y,z in degrees (default 0,0,0)");
    cmd->add_option("--field", o->field, "MR field strength for the t1 grid: 1.5 or 3 (default 1.5)");
    cmd->add_option("--preset", o->preset, "lumbar: average, overweight or calcified (default average)")
        ->check(CLI::IsMember({"average", "overweight", "calcified"}));
    cmd->add_option("--bmi", o->bmi, "lumbar: body-mass index in kg/m^2; scales the layers above the epidural space")
        ->check(CLI::Range(10.0, 80.0));
    cmd->add_option(
        "--layers", o->layers, "slab: tissue:mm,... from the surface down (default skin:2,fat:8,muscle:20)");
    cmd->add_option("--tilt", o->tilt, "slab: tilt of the layers about x in degrees (default 0)")
        ->check(CLI::Range(-75.0, 75.0));
    cmd->add_option("--radius", o->radius, "sphere: radius in mm (default 10)");
    cmd->add_option("--thickness", o->thickness, "sphere: slab thickness in mm (default 40)");
    cmd->add_option("--slab-tissue", o->slabTissue, "sphere: tissue of the slab (default fat)");
    cmd->add_option("--sphere-tissue", o->sphereTissue, "sphere: tissue of the sphere (default muscle)");
    cmd->add_option("--lesion-radius", o->lesionRadius, "torso: lesion radius in mm (default 8)");
    cmd->add_option("--scan-pair", o->scanPair,
        "Instead of one volume, write a CT and a moved MR of the phantom into this folder, as scanners export "
        "them: ct.nrrd (hu at --spacing), mr.nrrd with a BIDS sidecar (a T1 map with Rician noise), and "
        "truth.txt (the true MR-from-CT map, 4x4 LPS): a pair for `voxhap fuse` with a known answer");
    cmd->add_option("--mr-turn", o->mrTurn,
        "--scan-pair: the body's rotation in the MR about x,y,z in degrees, about its centre (default 0,0,0)");
    cmd->add_option("--mr-shift", o->mrShift, "--scan-pair: the body's shift in the MR, x,y,z in mm (default 0,0,0)");
    cmd->add_option("--mr-spacing", o->mrSpacing, "--scan-pair: the MR's voxel size in mm (default 1,1,4)");
    cmd->add_option("--mr-noise", o->mrNoise, "--scan-pair: Rician noise as a fraction of muscle's T1 (default 0.05)")
        ->check(CLI::Range(0.0, 1.0));
    cmd->add_option("--seed", o->seed, "--scan-pair: the noise's seed (default 1)");
    addCommonOptions(*cmd, o->common);
    return [o, cmd] { return run(*o, *cmd); };
}

} // namespace voxhap::tools
