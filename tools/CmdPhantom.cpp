// SPDX-License-Identifier: Apache-2.0
/// @file CmdPhantom.cpp
/// @brief `voxhap phantom <kind>`: generate a synthetic volume and save it as .vdb.

#include "tools/Cli.h"
#include "tools/InfoReport.h"

#include "volume/phantoms/Phantoms.h"
#include "volume/io/VdbFile.h"

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
};

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
    addCommonOptions(*cmd, o->common);
    return [o, cmd] { return run(*o, *cmd); };
}

} // namespace voxhap::tools
