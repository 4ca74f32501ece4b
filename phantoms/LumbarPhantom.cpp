// SPDX-License-Identifier: Apache-2.0
/// @file LumbarPhantom.cpp
/// @brief Lumbar epidural phantom: midline layers from [S19] Table I presets and
/// the tissue table, optional BMI scaling (physics.md §2.3, §3.3), and two
/// vertebrae (cortical shell, cancellous core) beside and below the path.

#include "phantoms/Phantoms.h"

#include "core/Errors.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace voxhap::volume {

namespace {

// Geometry of the vertebrae around the midline path [mm, chosen]: typical
// adult lumbar proportions, sized so that the midline path at x = z = 0 passes
// between the spinous processes and laminae and ends on a vertebral body.
constexpr double kMidlineHalfWidth = 5.0; ///< supraspinous/interspinous ligament and spinous process, |x|
constexpr double kLaminaHalfWidth = 18.0; ///< laminae and pedicles, |x|
constexpr double kCanalHalfWidth = 11.0;  ///< spinal canal, |x|
constexpr double kSacHalfWidth = 8.0;     ///< thecal sac (dura + CSF), |x|
constexpr double kBodyHalfWidth = 20.0;   ///< vertebral body, |x|
constexpr double kInterspinousGap = 12.0; ///< gap between spinous processes and laminae, along z
constexpr double kBodyHeight = 30.0;      ///< vertebral body height along z
constexpr double kDiscHeight = 10.0;      ///< intervertebral disc height along z
constexpr double kBodyStartZ = -4.0;      ///< lower endplate of the upper body: the path meets bone
constexpr double kBodyDepth = 30.0;       ///< vertebral body depth (anterior-posterior)
constexpr double kAnteriorEpidural = 1.0; ///< epidural space in front of the thecal sac
constexpr double kMuscleBelow = 10.0;     ///< muscle (psoas) below the vertebral body
constexpr double kHalfExtent = 40.0;      ///< block half size in x and z
constexpr double kAirAbove = 5.0;         ///< air above the skin

// [S19] Table I: derma length and epidural space length per patient type (physics.md §2.3).
struct PresetRow {
    LumbarPreset preset;
    const char* name;
    double dermaMm;
    double epiduralMm;
};
constexpr PresetRow kPresets[] = {
    {LumbarPreset::Average, "average", 10.0, 6.0},
    {LumbarPreset::Overweight, "overweight", 30.0, 4.0},
    {LumbarPreset::Calcified, "calcified", 10.0, 4.0},
};

const PresetRow& presetRow(LumbarPreset p)
{
    return *std::find_if(std::begin(kPresets), std::end(kPresets), [p](const PresetRow& r) { return r.preset == p; });
}

double defaultThickness(const TissueTable& table, const char* name)
{
    const Tissue& t = table.at(name);
    if (!t.thickness) throw ValueError(table.origin() + ": tissue '" + t.name + "' has no 'thickness'");
    return t.thickness->value;
}

} // namespace

LumbarPreset parseLumbarPreset(const std::string& name)
{
    for (const auto& r : kPresets) {
        if (name == r.name) return r.preset;
    }
    throw ValueError("unknown lumbar preset '" + name + "' (expected average, overweight or calcified)");
}

std::string lumbarPresetName(LumbarPreset p) { return presetRow(p).name; }

LumbarLayout lumbarLayout(const LumbarParams& p, const TissueTable& table)
{
    const PresetRow& row = presetRow(p.preset);
    LumbarLayout l;
    l.skin = defaultThickness(table, "skin");
    if (row.dermaMm <= l.skin) throw ValueError("lumbar phantom: derma thinner than the skin layer");
    l.fat = row.dermaMm - l.skin; // [S19] "derma length": skin plus subcutaneous fat [chosen reading]
    l.supraspinous = defaultThickness(table, "supraspinous_ligament");
    l.interspinous = defaultThickness(table, "interspinous_ligament");
    l.flavum = defaultThickness(table, "ligamentum_flavum");
    l.epidural = row.epiduralMm;
    l.dura = defaultThickness(table, "dura");
    l.csf = defaultThickness(table, "csf");
    if (p.bmi) {
        const double bmi = *p.bmi;
        if (!std::isfinite(bmi) || bmi < 10.0 || bmi > 80.0) {
            throw ValueError("lumbar phantom: BMI " + std::to_string(bmi) + " outside 10..80 kg/m^2");
        }
        // physics.md §3.3: SED [cm] = 2.52 + 0.11·BMI (Melo et al. 2020); every layer above
        // the epidural space scales in proportion, the epidural space and dura do not.
        const double sedMm = 10.0 * (2.52 + 0.11 * bmi);
        l.scale = sedMm / l.sed();
        for (double* t : {&l.skin, &l.fat, &l.supraspinous, &l.interspinous, &l.flavum}) *t *= l.scale;
    }
    return l;
}

PhantomModel lumbarModel(const LumbarParams& p, const TissueTable& table)
{
    const LumbarLayout l = lumbarLayout(p, table);
    const auto id = [&](const char* name) { return table.at(name).id; };
    const int skin = id("skin"), fat = id("fat"), muscle = id("muscle");
    const int supra = id("supraspinous_ligament"), inter = id("interspinous_ligament"),
              flavum = id("ligamentum_flavum");
    const int epidural = id("epidural_space"), dura = id("dura"), csf = id("csf"), disc = id("intervertebral_disc");
    const int cortical = id("cortical_bone"), cancellous = id("cancellous_bone");
    const double shell = defaultThickness(table, "cortical_bone");

    // Depths of the layer bottoms along the midline [mm].
    const double skinEnd = l.skin, fatEnd = skinEnd + l.fat, supraEnd = fatEnd + l.supraspinous;
    const double interEnd = supraEnd + l.interspinous, flavumEnd = interEnd + l.flavum;
    const double epiduralEnd = flavumEnd + l.epidural, duraEnd = epiduralEnd + l.dura, csfEnd = duraEnd + l.csf;
    const double antDuraEnd = csfEnd + l.dura, canalEnd = antDuraEnd + kAnteriorEpidural;
    const double bodyEnd = canalEnd + kBodyDepth, blockEnd = bodyEnd + kMuscleBelow;
    const double halfGap = 0.5 * kInterspinousGap;

    // Bone: cortical within `shell` of the given free-surface distance.
    const auto bone = [=](double surfaceDistance) { return surfaceDistance < shell ? cortical : cancellous; };

    PhantomModel m;
    m.kind = "lumbar";
    std::ostringstream desc;
    desc << "lumbar epidural, preset " << lumbarPresetName(p.preset);
    if (p.bmi) desc << ", BMI " << *p.bmi << " (scale " << l.scale << ")";
    m.description = desc.str();
    m.classify = [=](const Vec3d& w) -> int {
        const double d = -w.y(), ax = std::abs(w.x()), az = std::abs(w.z()), z = w.z();
        if (d < 0.0 || d >= blockEnd) return 0;
        if (d < skinEnd) return skin;
        if (d < fatEnd) return fat;
        if (d < supraEnd) return ax <= kMidlineHalfWidth ? supra : muscle;
        if (d < interEnd) { // spinous processes, interspinous ligament between them
            if (ax > kMidlineHalfWidth) return muscle;
            if (az < halfGap) return inter;
            return bone(std::min({kMidlineHalfWidth - ax, d - supraEnd, az - halfGap}));
        }
        if (d < flavumEnd) { // laminae, ligamentum flavum between them
            if (ax > kLaminaHalfWidth) return muscle;
            if (az < halfGap) return flavum;
            double s = std::min(kLaminaHalfWidth - ax, az - halfGap);
            if (ax > kMidlineHalfWidth) s = std::min(s, d - interEnd); // posterior face, under muscle
            if (ax <= kCanalHalfWidth) s = std::min(s, flavumEnd - d); // anterior face, on the canal
            return bone(s);
        }
        if (d < canalEnd) { // spinal canal between the pedicles
            if (ax > kLaminaHalfWidth) return muscle;
            if (ax > kCanalHalfWidth) {
                if (az < halfGap) return epidural; // intervertebral foramen
                return bone(std::min({ax - kCanalHalfWidth, kLaminaHalfWidth - ax, az - halfGap}));
            }
            const bool inSac = ax <= kSacHalfWidth && d >= epiduralEnd && d < antDuraEnd;
            if (!inSac) return epidural;
            if (d < duraEnd || d >= csfEnd || ax > kSacHalfWidth - l.dura) return dura;
            return csf;
        }
        if (d < bodyEnd) { // vertebral bodies and discs, repeating along z
            if (ax > kBodyHalfWidth) return muscle;
            const double period = kBodyHeight + kDiscHeight;
            const double phase = std::fmod(std::fmod(z - kBodyStartZ, period) + period, period);
            if (phase >= kBodyHeight) return disc;
            return bone(std::min({kBodyHalfWidth - ax, d - canalEnd, bodyEnd - d, phase, kBodyHeight - phase}));
        }
        return muscle;
    };
    m.bounds = {Vec3d(-kHalfExtent, -blockEnd, -kHalfExtent), Vec3d(kHalfExtent, kAirAbove, kHalfExtent)};
    m.pathEntry = Vec3d::Zero();
    m.pathTarget = Vec3d(0.0, -blockEnd, 0.0);
    m.landmarks = {
        {"entry", m.pathEntry},
        {"epidural_target", Vec3d(0.0, -(flavumEnd + 0.5 * l.epidural), 0.0)},
        {"csf_target", Vec3d(0.0, -(duraEnd + 0.5 * l.csf), 0.0)},
        {"vertebral_body", Vec3d(0.0, -(canalEnd + 0.5 * kBodyDepth), 0.0)},
    };
    return m;
}

} // namespace voxhap::volume
