// SPDX-License-Identifier: Apache-2.0
/// @file ParseOnly.cpp
/// @brief Stand-ins for what the scene, insertion-script and session targets
/// link but never call: building a scene's volume, material grids and force
/// model, and running an insertion. The parsers share their source files with
/// that code; compiling it all with the sanitizers would add minutes to every
/// build for functions no parser reaches. Each stand-in aborts, so a parser
/// that ever reached one would be reported, not silently stubbed.

#include "haptic/beam/Foundation.h"
#include "haptic/force/NeedleForceModel.h"
#include "haptic/force/Palpation.h"
#include "haptic/materials/MaterialField.h"
#include "haptic/shaft/LabelTrace.h"
#include "haptic/shaft/ShaftIntegration.h"
#include "phantoms/Phantoms.h"
#include "volume/VolumeFile.h"

#include <cstdio>
#include <cstdlib>

namespace {
[[noreturn]] void notLinked(const char* what)
{
    std::fprintf(stderr, "fuzz: %s is not linked into the parser targets (fuzz/ParseOnly.cpp)\n", what);
    std::abort();
}
} // namespace

namespace voxhap::volume {
Volume loadVolume(const std::filesystem::path&, const LoadOptions&, DicomLoadReport*) { notLinked("loadVolume"); }
LumbarPreset parseLumbarPreset(const std::string&) { notLinked("parseLumbarPreset"); }
LumbarLayout lumbarLayout(const LumbarParams&, const TissueTable&) { notLinked("lumbarLayout"); }
PhantomModel phantomModel(const PhantomSpec&, const TissueTable&) { notLinked("phantomModel"); }
Volume makePhantom(const PhantomModel&, const GridSpec&, const TissueTable&) { notLinked("makePhantom"); }
std::optional<Vec3d> phantomLandmark(const Volume&, const std::string&) { notLinked("phantomLandmark"); }
} // namespace voxhap::volume

namespace voxhap::haptic {
MaterialField::MaterialField(const volume::Volume&, const volume::TissueTable&, const MaterialOptions&)
{
    notLinked("MaterialField");
}
SkinMap::SkinMap(
    const volume::Volume&, const volume::TissueTable&, const Vec3d&, const Vec3d&, const PalpationParams&, double)
{
    notLinked("SkinMap");
}
std::unique_ptr<ShaftIntegrator> makeIntegrator(const MaterialField&, const IntegratorOptions&)
{
    notLinked("makeIntegrator");
}
std::vector<LabelRun> traceLabelRuns(const MaterialField&, const Vec3d&, const Vec3d&, double)
{
    notLinked("traceLabelRuns");
}
std::unique_ptr<Foundation> makeLabelFoundation(const MaterialField&) { notLinked("makeLabelFoundation"); }
NeedleForceModel::NeedleForceModel(ForceModelSetup) { notLinked("NeedleForceModel"); }
void NeedleForceModel::step(const NeedleInput&, NeedleOutput&) noexcept { notLinked("NeedleForceModel::step"); }
} // namespace voxhap::haptic
