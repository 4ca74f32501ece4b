// SPDX-License-Identifier: Apache-2.0
/// @file MaterialLaws.h
/// @brief Image value -> mechanics: T1 -> damping density (physics.md §1.2, §5.4)
/// and HU -> bone density -> Young's modulus -> contact stiffness (§1.3, §5.3).
///
/// Every constant here is a named default with its source; tissue-specific
/// parameters live in data/tissues.json.
#pragma once

#include "volume/TissueTable.h"

#include <string>
#include <string_view>

namespace voxhap::haptic {

/// @brief Kyung Eq. 4, b = C1·exp(C2·T1), fitted per field strength (physics.md §5.4).
struct T1DampingLaw {
    double c1NsPerM2 = 0; ///< C1 [N·s/m²]
    double c2PerMs = 0;   ///< C2 [1/ms]
    double t1MinMs = 0;   ///< T1 clamp: fat [ms] (§5.4: clamp to the fat–muscle range)
    double t1MaxMs = 0;   ///< T1 clamp: muscle [ms]

    /// @brief Damping density [N·s/mm²] for a T1 [ms]; T1 clamped first, so the
    /// result is finite for any input (NaN maps to the lower clamp).
    double dampingNsPerMm2(double t1Ms) const;
};

/// @brief The §5.4 fit for a field strength: 1.5 T C1 = 2464 N·s/m², C2 = 1.398e-3 /ms,
/// clamp 290..856 ms; 3 T C1 = 2058, C2 = 1.533e-3, clamp 382..898 ms.
T1DampingLaw t1DampingLaw(volume::FieldStrength field);

/// @brief Density–modulus relations of physics.md §5.3 (E in MPa, ρ in g/cm³).
enum class ModulusLaw {
    Morgan2003,            ///< E = 4730·ρ^1.56, apparent density, vertebra
    Keller1994,            ///< E = 1890·ρ^1.92, ash density, spine
    Kopperdahl2002,        ///< E = −34.7 + 3230·ρ, QCT density, vertebra
    KopperdahlKeaveny1998, ///< E = −80 + 2100·ρ, apparent density, spine
    Keaveny1997,           ///< E = −58 + 1540·ρ, apparent density, lumbar
};

/// @brief Parse "morgan2003", "keller1994", "kopperdahl2002", "kopperdahl-keaveny1998"
/// or "keaveny1997". @throw ValueError listing the names
ModulusLaw parseModulusLaw(std::string_view name);
std::string modulusLawName(ModulusLaw law);

/// @brief Young's modulus [MPa = N/mm²] from density [g/cm³]; never negative.
double youngsModulusMPa(ModulusLaw law, double densityGPerCm3);

/// @brief Fallback HU -> density calibration without a phantom: 0.001·HU g/cm³
/// (physics.md §5.3 [chosen], ±30 %), never negative.
double densityFromHu(double hu);

/// @brief Hooke contact stiffness k = E·A_tip/L_c [N/mm] (physics.md §1.3),
/// with E [MPa], tip area [mm²] and characteristic length L_c [mm] (one voxel).
double contactStiffnessNPerMm(double youngsModulusMPa, double tipAreaMm2, double lengthMm);

} // namespace voxhap::haptic
