// SPDX-License-Identifier: Apache-2.0
/// @file MaterialLaws.cpp
/// @brief The constants of physics.md §5.3 and §5.4.

#include "haptic/materials/MaterialLaws.h"

#include "core/Errors.h"

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

namespace {

// physics.md §5.4: fit of b = C1·exp(C2·T1) to beta_fat = 3696 and beta_muscle = 8152 N·s/m²,
// with T1 of fat and muscle from §5.1 (de Bazelaire 2004).
constexpr T1DampingLaw kLaw1p5T{2464.0, 1.398e-3, 290.0, 856.0};
constexpr T1DampingLaw kLaw3T{2058.0, 1.533e-3, 382.0, 898.0};

constexpr double kNsPerM2ToNsPerMm2 = 1e-6; // 1 m² = 1e6 mm²

// physics.md §5.3 [chosen]: without a calibration phantom, rho_QCT ≈ 0.001·HU g/cm³ (±30 %).
constexpr double kDensityPerHu = 0.001;

} // namespace

double T1DampingLaw::dampingNsPerMm2(double t1Ms) const
{
    // Clamp first: T1 = 65535 would give exp(91.6) ≈ 6e39 (§5.4); NaN goes to the lower bound.
    const double t1 = std::isnan(t1Ms) ? t1MinMs : std::clamp(t1Ms, t1MinMs, t1MaxMs);
    return c1NsPerM2 * std::exp(c2PerMs * t1) * kNsPerM2ToNsPerMm2;
}

T1DampingLaw t1DampingLaw(volume::FieldStrength field)
{
    return field == volume::FieldStrength::T3 ? kLaw3T : kLaw1p5T;
}

ModulusLaw parseModulusLaw(std::string_view name)
{
    for (ModulusLaw law : {ModulusLaw::Morgan2003, ModulusLaw::Keller1994, ModulusLaw::Kopperdahl2002,
             ModulusLaw::KopperdahlKeaveny1998, ModulusLaw::Keaveny1997}) {
        if (modulusLawName(law) == name) return law;
    }
    throw ValueError("unknown modulus law '" + std::string(name) +
        "' (expected morgan2003, keller1994, kopperdahl2002, kopperdahl-keaveny1998 or keaveny1997)");
}

std::string modulusLawName(ModulusLaw law)
{
    switch (law) {
    case ModulusLaw::Morgan2003:
        return "morgan2003";
    case ModulusLaw::Keller1994:
        return "keller1994";
    case ModulusLaw::Kopperdahl2002:
        return "kopperdahl2002";
    case ModulusLaw::KopperdahlKeaveny1998:
        return "kopperdahl-keaveny1998";
    case ModulusLaw::Keaveny1997:
        return "keaveny1997";
    }
    return "?";
}

double youngsModulusMPa(ModulusLaw law, double rho)
{
    if (!(rho > 0.0)) return 0.0; // also catches NaN
    double e = 0.0;
    switch (law) { // physics.md §5.3, coefficients as tabulated in public spine FE code
    case ModulusLaw::Morgan2003:
        e = 4730.0 * std::pow(rho, 1.56);
        break;
    case ModulusLaw::Keller1994:
        e = 1890.0 * std::pow(rho, 1.92);
        break;
    case ModulusLaw::Kopperdahl2002:
        e = -34.7 + 3230.0 * rho;
        break;
    case ModulusLaw::KopperdahlKeaveny1998:
        e = -80.0 + 2100.0 * rho;
        break;
    case ModulusLaw::Keaveny1997:
        e = -58.0 + 1540.0 * rho;
        break;
    }
    return std::isfinite(e) ? std::max(e, 0.0) : 0.0;
}

double densityFromHu(double hu) { return std::isfinite(hu) ? std::max(0.0, kDensityPerHu * hu) : 0.0; }

double contactStiffnessNPerMm(double e, double tipAreaMm2, double lengthMm)
{
    if (!(lengthMm > 0.0)) return 0.0;
    return e * tipAreaMm2 / lengthMm; // N/mm² · mm² / mm = N/mm
}

} // namespace voxhap::haptic
