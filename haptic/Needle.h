// SPDX-License-Identifier: Apache-2.0
/// @file Needle.h
/// @brief The needle: gauge, tip type and length (physics.md §1.3, §3.3), and
/// what its bending reads: material, wall, stylet and bevel (physics.md §9.1).
#pragma once

#include <string>

namespace voxhap::haptic {

/// @brief Needle tip shapes (physics.md §3.3); their slope multipliers are the
/// Conci model's (ConciModel.h).
enum class TipType {
    Coned,
    Bevel,
    Triangular
};

/// @brief What the needle tube is made of (physics.md §9.1).
enum class NeedleMaterial {
    StainlessSteel, ///< AISI 304, E = 193 GPa
    Nitinol         ///< austenite, E = 75 GPa
};

struct Needle {
    int gauge = 18;               ///< Birmingham gauge, 14..27
    TipType tip = TipType::Bevel; ///< coned, bevel (Tuohy, Quincke) or triangular (trocar)
    double lengthMm = 90.0;       ///< shaft length [mm] (a 3.5-inch spinal needle)
    int referenceGauge = 18;      ///< gauge the force tables were measured with [chosen]

    // Bending (physics.md §9.1); read only when the scene's bending term is on.
    NeedleMaterial material = NeedleMaterial::StainlessSteel;
    double youngsModulusMPa = 0.0;     ///< E [MPa = N/mm²]; 0: the material's
    double innerDiameterGivenMm = -1.; ///< ID [mm]; negative: the gauge's ISO 9626 regular wall
    bool stylet = false;               ///< a stylet fills the lumen and adds to EI
    double bevelAngleDeg = 20.0;       ///< angle of the bevel face to the axis, in (0, 90) [chosen, unverified]
    double bevelOrientationDeg = 0.0;  ///< where the bevel pushes the tip, about the shaft (§9.3)

    /// @brief Nominal outer diameter [mm] (ISO 9626 regular-wall table).
    double outerDiameterMm() const;
    /// @brief Tip cross-section π·d²/4 [mm²]: 1.27 mm² for 18 G (physics.md §1.3).
    double tipAreaMm2() const;
    /// @brief Puncture and cutting forces scale with the diameter relative to the
    /// reference gauge: F ∝ d [chosen, calibrate]; [C-ui] notes that "diameter
    /// matters too" (§3.3) without a law, and a cutting force proportional to the
    /// cut length (the circumference) is the simplest reading.
    double forceScale() const;

    /// @brief E [MPa]: the given one, else the material's.
    double youngsModulus() const;
    /// @brief Inner diameter [mm]: the given one, else ISO 9626 regular wall.
    double innerDiameterMm() const;
    /// @brief EI [N·mm²] of the tube, plus a solid stylet of the lumen's diameter if fitted.
    double bendingStiffnessNmm2() const;
    /// @brief The tip is asymmetric (a bevel): it feels a lateral force (§9.3).
    bool asymmetricTip() const { return tip == TipType::Bevel; }
};

/// @throw ValueError on a gauge outside 14..27
double gaugeInnerDiameterMm(int gauge);
/// @brief E [MPa] of a needle material (physics.md §9.1).
double materialModulusMPa(NeedleMaterial m);
/// @brief "stainless_steel", "nitinol". @throw ValueError
NeedleMaterial parseNeedleMaterial(const std::string& name);
const char* needleMaterialName(NeedleMaterial m);

/// @throw ValueError on a gauge outside 14..27
double gaugeOuterDiameterMm(int gauge);
/// @brief "coned", "bevel", "triangular". @throw ValueError
TipType parseTipType(const std::string& name);
const char* tipTypeName(TipType t);

} // namespace voxhap::haptic
