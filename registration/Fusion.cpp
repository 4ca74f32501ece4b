// SPDX-License-Identifier: Apache-2.0
/// @file Fusion.cpp
/// @brief The input checks, then registration, resampling and the record.

#include "registration/Fusion.h"

#include "core/Errors.h"
#include "core/Format.h"
#include "registration/TransformFile.h"
#include "volume/Grids.h"

#include <algorithm>
#include <cctype>
#include <chrono>

namespace voxhap::registration {

using volume::Channel;
using volume::Volume;

namespace {

/// A PatientName as written by different exports: case and trailing empty
/// components ("DOE^JOHN^^" and "Doe^John") do not make another patient.
std::string normalisedName(std::string s)
{
    for (char& c : s) c = char(std::toupper(static_cast<unsigned char>(c)));
    while (!s.empty() && (s.back() == '^' || s.back() == ' ')) s.pop_back();
    return s;
}

std::string sourceOf(const std::string& file, const std::string& source)
{
    return source.empty() ? file : file + " (" + source + ")";
}

} // namespace

void checkFusionInputs(const Volume& ct, const Volume& mr, const FusionOptions& o)
{
    const bool ctIsMr = !ct.has(Channel::Hu) && (ct.has(Channel::T1) || ct.has(Channel::Intensity));
    const bool mrIsCt = mr.has(Channel::Hu) && !mr.has(Channel::T1) && !mr.has(Channel::Intensity);
    if (ctIsMr && mrIsCt) {
        throw ValueError(
            o.ctFile + ": this is the MR and " + o.mrFile + " is the CT: give the CT first (voxhap fuse CT MR)");
    }
    if (ctIsMr) {
        throw ValueError(o.ctFile + ": given as the CT, but it is an MR (" +
            (ct.metadata().mrWeighting ? std::string(volume::mrWeightingName(*ct.metadata().mrWeighting))
                                       : std::string("no hu grid")) +
            ")");
    }
    if (!ct.has(Channel::Hu)) throw ValueError(o.ctFile + ": given as the CT, but it has no hu grid");
    if (mrIsCt) throw ValueError(o.mrFile + ": given as the MR, but it is a CT (an hu grid, no MR channel)");
    if (!mr.has(Channel::T1) && !mr.has(Channel::Intensity)) {
        throw ValueError(o.mrFile + ": given as the MR, but it has neither a t1 nor an intensity grid");
    }
    if (mr.has(Channel::Hu)) {
        throw ValueError(o.mrFile +
            ": given as the MR, but it holds an hu grid too (a fused or phantom volume): "
            "give the MR scan alone");
    }
    const Vec3i d = mr.indexBox().dims();
    if (d.minCoeff() < 2) {
        throw ValueError(o.mrFile + ": the MR is " + std::to_string(d.x()) + " x " + std::to_string(d.y()) + " x " +
            std::to_string(d.z()) + " voxels: one slice cannot be registered in 3D");
    }
    const Vec3i c = ct.indexBox().dims();
    if (c.minCoeff() < 2) {
        throw ValueError(o.ctFile + ": the CT is " + std::to_string(c.x()) + " x " + std::to_string(c.y()) + " x " +
            std::to_string(c.z()) + " voxels: one slice cannot be registered in 3D");
    }
}

void checkSamePatient(const PatientIdentity& ct, const PatientIdentity& mr, const FusionOptions& o)
{
    if (!ct.id.empty() && !mr.id.empty() && ct.id != mr.id) {
        throw ValueError(o.mrFile + ": PatientID '" + mr.id + "' differs from " + o.ctFile + "'s '" + ct.id +
            "': these may be two patients (--different-patients fuses them anyway)");
    }
    if (!ct.name.empty() && !mr.name.empty() && normalisedName(ct.name) != normalisedName(mr.name)) {
        throw ValueError(o.mrFile + ": PatientName differs from " + o.ctFile +
            "'s: these may be two patients (--different-patients fuses them anyway)");
    }
}

FusionResult fuse(const Volume& ct, const Volume& mr, const FusionOptions& o)
{
    const auto t0 = std::chrono::steady_clock::now();
    checkFusionInputs(ct, mr, o);
    FusionResult out{Volume(ct.transformPtr()->copy(), ct.indexBox()), {}, {}, {}, 0.0};
    try {
        out.registration = registerMrToCt(ct, mr, o.registration);
    } catch (const ValueError& e) {
        throw ValueError(o.mrFile + ": " + e.what());
    }
    const Channel moving = movingChannel(mr);
    out.volume.setGrid(Channel::Hu, std::const_pointer_cast<openvdb::GridBase>(ct.grid(Channel::Hu))->copyGrid());
    out.volume.setGrid(moving, resampleOnto(ct, mr, moving, out.registration.mrFromCt, &out.resample));
    out.transformText = itkTransformText(out.registration.mrFromCt);

    volume::VolumeMetadata& md = out.volume.metadata();
    md = ct.metadata();
    // The MR's facts that decide its material: what it is, what its t1 grid
    // holds, and the field strength whose T1 law applies (physics.md §5.4).
    md.mrWeighting = mr.metadata().mrWeighting;
    md.t1Kind = mr.metadata().t1Kind;
    md.fieldStrength = mr.metadata().fieldStrength;
    md.fieldStrengthSource = mr.metadata().fieldStrengthSource;
    md.fieldStrengthTesla = mr.metadata().fieldStrengthTesla;
    md.bodyWidthMm = mr.metadata().bodyWidthMm;
    md.description = "CT " + o.ctFile + " with MR " + o.mrFile + " registered onto it";
    volume::FusionRecord rec;
    const RegistrationResult& r = out.registration;
    rec.mrFromCt = r.mrFromCt.matrix();
    rec.itkTransform = out.transformText;
    rec.startedFrom = r.startedFrom;
    rec.metricGeometry = r.metricGeometry;
    rec.metricStart = r.metricStart;
    rec.metricFinal = r.metricFinal;
    rec.iterations = r.iterations;
    rec.stopReason = r.stopReason;
    rec.converged = r.converged;
    rec.warnings = r.warnings;
    rec.overlapStart = r.overlapStart;
    rec.overlapFinal = r.overlapFinal;
    rec.surfaceDistanceMm = r.surfaceDistanceMm;
    rec.surfaceLimitMm = r.surfaceLimitMm;
    rec.channelSources["hu"] = sourceOf(o.ctFile, o.ctSource);
    rec.channelSources[std::string(volume::channelName(moving))] = sourceOf(o.mrFile, o.mrSource) + ", registered (" +
        (o.registration.affine ? "rigid then affine" : "rigid") + ") and resampled trilinearly";
    rec.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    md.fusion = rec;
    out.seconds = rec.seconds;
    return out;
}

} // namespace voxhap::registration
