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

double Needle::outerDiameterMm() const { return gaugeOuterDiameterMm(gauge); }

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
