// SPDX-License-Identifier: Apache-2.0
/// @file Needle.h
/// @brief The needle: gauge, tip type and length (physics.md §1.3, §3.3).
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

struct Needle {
    int gauge = 18;               ///< Birmingham gauge, 14..27
    TipType tip = TipType::Bevel; ///< coned, bevel (Tuohy, Quincke) or triangular (trocar)
    double lengthMm = 90.0;       ///< shaft length [mm] (a 3.5-inch spinal needle)
    int referenceGauge = 18;      ///< gauge the force tables were measured with [chosen]

    /// @brief Nominal outer diameter [mm] (ISO 9626 regular-wall table).
    double outerDiameterMm() const;
    /// @brief Tip cross-section π·d²/4 [mm²]: 1.27 mm² for 18 G (physics.md §1.3).
    double tipAreaMm2() const;
    /// @brief Puncture and cutting forces scale with the diameter relative to the
    /// reference gauge: F ∝ d [chosen, calibrate]; [C-ui] notes that "diameter
    /// matters too" (§3.3) without a law, and a cutting force proportional to the
    /// cut length (the circumference) is the simplest reading.
    double forceScale() const;
};

/// @throw ValueError on a gauge outside 14..27
double gaugeOuterDiameterMm(int gauge);
/// @brief "coned", "bevel", "triangular". @throw ValueError
TipType parseTipType(const std::string& name);
const char* tipTypeName(TipType t);

} // namespace voxhap::haptic
