// SPDX-License-Identifier: Apache-2.0
/// @file Needle.cpp
#include "haptic/Needle.h"

#include "core/Errors.h"
#include "core/Math.h"

#include <string>

namespace voxhap::haptic {

double gaugeOuterDiameterMm(int gauge)
{
    // ISO 9626:2016 nominal outer diameters [mm], 14 G to 27 G.
    static constexpr double kOd[] = {
        2.108, 1.829, 1.651, 1.473, 1.270, 1.067, 0.908, 0.819, 0.718, 0.641, 0.565, 0.515, 0.464, 0.413};
    if (gauge < 14 || gauge > 27) throw ValueError("needle: gauge " + std::to_string(gauge) + " outside 14..27");
    return kOd[gauge - 14];
}

double gaugeInnerDiameterMm(int gauge)
{
    // Nominal inner diameters of regular-wall tubing [mm], 14 G to 27 G, from the same
    // gauge chart as the outer diameters (ISO 9626 regular wall; physics.md §9.1).
    static constexpr double kId[] = {
        1.600, 1.372, 1.194, 1.067, 0.838, 0.686, 0.603, 0.514, 0.413, 0.337, 0.311, 0.260, 0.260, 0.210};
    if (gauge < 14 || gauge > 27) throw ValueError("needle: gauge " + std::to_string(gauge) + " outside 14..27");
    return kId[gauge - 14];
}

double materialModulusMPa(NeedleMaterial m)
{
    // physics.md §9.1: AISI 304 stainless steel 193 GPa; nitinol (austenite) 75 GPa.
    return m == NeedleMaterial::Nitinol ? 75e3 : 193e3;
}

NeedleMaterial parseNeedleMaterial(const std::string& name)
{
    if (name == "stainless_steel") return NeedleMaterial::StainlessSteel;
    if (name == "nitinol") return NeedleMaterial::Nitinol;
    throw ValueError("needle: unknown material '" + name + "' (stainless_steel, nitinol)");
}

const char* needleMaterialName(NeedleMaterial m)
{
    return m == NeedleMaterial::Nitinol ? "nitinol" : "stainless_steel";
}

double Needle::outerDiameterMm() const { return gaugeOuterDiameterMm(gauge); }

double Needle::youngsModulus() const
{
    return youngsModulusMPa > 0.0 ? youngsModulusMPa : materialModulusMPa(material);
}

double Needle::innerDiameterMm() const
{
    return innerDiameterGivenMm >= 0.0 ? innerDiameterGivenMm : gaugeInnerDiameterMm(gauge);
}

double Needle::bendingStiffnessNmm2() const
{
    // I = π(D⁴ − d⁴)/64 for the tube; a stylet of the lumen's diameter adds π·d⁴/64
    // (the same material [chosen]), which makes the pair a solid rod.
    const double D = outerDiameterMm(), d = innerDiameterMm();
    const double d4 = stylet ? 0.0 : d * d * d * d;
    return youngsModulus() * kPi * (D * D * D * D - d4) / 64.0;
}

double Needle::tipAreaMm2() const
{
    const double d = outerDiameterMm();
    return kPi * d * d / 4.0;
}

double Needle::forceScale() const { return outerDiameterMm() / gaugeOuterDiameterMm(referenceGauge); }

TipType parseTipType(const std::string& name)
{
    if (name == "coned") return TipType::Coned;
    if (name == "bevel") return TipType::Bevel;
    if (name == "triangular") return TipType::Triangular;
    throw ValueError("needle: unknown tip '" + name + "' (coned, bevel, triangular)");
}

const char* tipTypeName(TipType t)
{
    switch (t) {
    case TipType::Coned:
        return "coned";
    case TipType::Bevel:
        return "bevel";
    case TipType::Triangular:
        return "triangular";
    }
    return "?";
}

} // namespace voxhap::haptic
