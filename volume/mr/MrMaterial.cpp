// SPDX-License-Identifier: Apache-2.0
/// @file MrMaterial.cpp
/// @brief The MR channel decision, background and T1 normalisation, in order.

#include "volume/mr/MrMaterial.h"

#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/mr/BodyWidth.h"
#include "volume/mr/T1Normalisation.h"

#include <sstream>

namespace voxhap::volume {

MrMaterialReport assignMrMaterial(
    Volume& v, MrWeighting weighting, const MrMaterialOptions& options, const std::string& source)
{
    Volume::GridPtr raw = std::const_pointer_cast<openvdb::GridBase>(v.grid(Channel::Intensity));
    if (!raw) throw ValueError(source + ": no MR intensities to assign");
    MrMaterialReport report;
    VolumeMetadata& md = v.metadata();
    if (options.t1Map) {
        weighting.kind = MrWeightingKind::T1Map;
        weighting.name = std::string(mrWeightingName(MrWeightingKind::T1Map));
        weighting.reason = "declared by the user (--t1-map)";
    } else if (options.t1Weighted && !weighting.fillsT1()) {
        weighting.reason = "declared by the user (--t1-weighted); the headers said: " + weighting.name +
            (weighting.reason.empty() ? "" : " (" + weighting.reason + ")");
        weighting.kind = MrWeightingKind::T1Weighted;
        weighting.name = std::string(mrWeightingName(MrWeightingKind::T1Weighted));
    }
    report.weighting = weighting;
    md.mrWeighting = weighting.kind;
    md.extra["mr_weighting_reason"] = weighting.reason;
    md.intensityUnits = "arbitrary units";

    // 1. Air. Grids are shared read-only once set: the rule runs on a copy.
    if (options.removeBackground && weighting.kind != MrWeightingKind::Phase) {
        Volume::GridPtr copy = raw->deepCopyGrid();
        report.background = removeMrBackground(*copy, v.indexBox());
        v.setGrid(Channel::Intensity, copy);
        md.extra["mr_background"] = report.background->rule;
    } else {
        md.extra["mr_background"] =
            options.removeBackground ? "none: a phase image has no air of noise around zero" : "none: switched off";
    }

    // 2.–4. The channel.
    const auto toT1 = [&v] {
        v.setGrid(Channel::T1, std::const_pointer_cast<openvdb::GridBase>(v.grid(Channel::Intensity)));
        v.removeGrid(Channel::Intensity);
    };
    if (weighting.kind == MrWeightingKind::T1Map) {
        toT1();
        md.t1Units = "ms";
        md.t1Kind = T1Kind::Map;
        report.channel = Channel::T1;
        report.note = "T1 map: values are T1 [ms]";
        return report;
    }
    if (weighting.kind != MrWeightingKind::T1Weighted) {
        report.note = "MR " + weighting.name + ": an intensity grid, not T1";
        return report;
    }
    if (!options.normaliseT1Weighted) {
        report.note = "T1-weighted, normalisation switched off: an intensity grid, not T1";
        md.extra["t1_norm_refused"] = "switched off";
        return report;
    }
    // The rule pins a trunk's fat and muscle (physics.md §5.1). In a head the
    // brightest class is white matter and there is no muscle to pin: a body
    // narrower than a trunk everywhere it was measured whole is not normalised.
    // A body the field of view cuts left and right (a sagittal spine slab) may
    // be a trunk: the rule applies, as it always did.
    const BodyWidth width = measureBodyWidth(v, *v.grid(Channel::Intensity));
    md.bodyWidthMm = std::max(width.widestMm, width.widestCutMm);
    if (width.measured() && !width.trunk()) {
        const std::string why = "the body is at most " + std::to_string(int(std::lround(width.widestMm))) +
            " mm across (a trunk is at least " + std::to_string(int(kMinTorsoWidthMm)) +
            " mm): a head or a limb, where the per-scan rule's fat and muscle (physics.md 5.1) "
            "are not the scan's brightest and middle classes";
        md.extra["t1_norm_refused"] = why;
        report.note = "T1-weighted but not normalised (" + why + "): an intensity grid, not T1";
        return report;
    }
    if (!width.measured()) {
        md.extra["t1_norm_anatomy"] =
            "the field of view cuts the body left and right in every section: taken as a trunk";
    }
    if (!md.fieldStrength) {
        // The table's fat and muscle T1 are known at 1.5 T and 3 T only (physics.md §5.4).
        std::ostringstream why;
        why << "the scan's field strength";
        if (md.fieldStrengthTesla) why << " (" << *md.fieldStrengthTesla << " T)";
        why << " is neither 1.5 T nor 3 T, the fields the tissue table gives fat and muscle T1 at";
        md.extra["t1_norm_refused"] = why.str();
        report.note = "T1-weighted but not normalised (" + why.str() + "): an intensity grid, not T1";
        return report;
    }
    const FieldStrength field = *md.fieldStrength;
    toT1();
    try {
        applyT1wNormalisation(v, fitT1wNormalisation(v, TissueTable::builtin(), field, source));
        report.channel = Channel::T1;
        report.note = "T1-weighted, normalised per scan to T1 [ms] at " + std::string(fieldStrengthName(field));
    } catch (const ValueError& e) {
        // Back to intensity: a T1-weighted signal that could not be normalised is not T1.
        v.setGrid(Channel::Intensity, std::const_pointer_cast<openvdb::GridBase>(v.grid(Channel::T1)));
        v.removeGrid(Channel::T1);
        md.extra["t1_norm_refused"] = e.what();
        report.note = "T1-weighted but not normalised (" + std::string(e.what()) + "): an intensity grid, not T1";
    }
    return report;
}

} // namespace voxhap::volume
