// SPDX-License-Identifier: Apache-2.0
/// @file Layer.h
/// @brief One tissue layer on the needle's path, with everything the layered
/// force models read from it (physics.md §2–§4).
///
/// Every layered model is one parameterisation of the same layer:
/// - an elastic (tip) stage while the layer is intact and pushed by the tip:
///   F = c0 + c1·z + c2·z² + c3·z³, z the tip's travel since it met the layer.
///   Sénac tenting (§2.1 Eq. 4) is c1 = a1, c2 = a2; Conci's elastic stage (§3.1)
///   is Ce0..Ce3; [LP] f_tip = k·x (§4 Eq. 2) is c1 = k, with no puncture force
///   and the layer's thickness as the puncture depth;
/// - puncture ("pop") when F reaches punctureForceN or z reaches punctureDepthMm;
/// - after puncture, Coulomb-type resistance rendered by the stick-slip proxy
///   (§6.2): the layer's cutting force summed over every entered layer (Sénac's
///   nested boxes, §2.1 Eq. 3), plus at the tip the plateau P(w) = p0 + p1·w + p2·w²
///   (Conci's plastic stage, w past the puncture depth) and the Coulomb friction C
///   ([LP] Eq. 3);
/// - viscous shaft friction b·v·l over the length l of the shaft in the layer ([LP]).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <string>

namespace voxhap::haptic {

/// @brief What a layer means to the insertion events (physics.md §2.3).
enum class LayerRole : std::uint8_t {
    Tissue,   ///< any other tissue
    Air,      ///< outside the body, or a gap
    Skin,     ///< its puncture is "skin entry"
    Ligament, ///< supraspinous, interspinous, flavum: the syringe plunger meets resistance
    Epidural, ///< entering it is the loss of resistance
    Dura,     ///< its puncture ends an epidural (and is the aim of a lumbar puncture)
    Csf,      ///< cerebrospinal fluid
    Bone,     ///< rigid: contact, not cutting (physics.md §1.3)
    Critical, ///< must not be touched: force to zero and a warning (§1.1)
};

/// @brief The role of a tissue or table row by name, e.g. "ligamentum_flavum" → Ligament.
LayerRole roleFromName(const std::string& name, bool rigid, bool critical);
const char* roleName(LayerRole r);

inline constexpr double kNoLimit = std::numeric_limits<double>::infinity();

struct Layer {
    std::string name; ///< tissue or table row name
    int label = -1;   ///< tissue id, -1 for a fixed-table row
    LayerRole role = LayerRole::Tissue;
    double startMm = 0; ///< depth along the path where the layer begins [mm]
    double endMm = 0;   ///< ... and ends [mm]

    // Elastic stage (intact layer pushed by the tip).
    std::array<double, 4> elastic{};   ///< c0 [N], c1 [N/mm], c2 [N/mm²], c3 [N/mm³]
    double punctureForceN = kNoLimit;  ///< pops when the elastic force reaches this [N]
    double punctureDepthMm = kNoLimit; ///< ... or when the tip has pushed this far [mm]
    bool tents = false;                ///< has an elastic stage; otherwise it is entered at once
    bool rigid = false;                ///< bone rendered as contact: the tip stops on it (§1.3)

    // After puncture.
    double cuttingForceN = 0;        ///< nested-box cutting force, summed over entered layers [N]
    std::array<double, 3> plateau{}; ///< tip-only plateau p0 [N], p1 [N/mm], p2 [N/mm²] of w
    double coulombN = 0;             ///< tip-only Coulomb friction C [N]
    double viscousNsPerMm2 = 0;      ///< shaft viscous friction b [N·s/mm²]: force b·v·l

    double lorResistance = 0; ///< syringe plunger resistance, 0 (free) .. 1 (blocked)

    double thicknessMm() const { return endMm - startMm; }
    /// @brief Elastic force at push depth z [N].
    double elasticForceN(double z) const noexcept
    {
        return elastic[0] + z * (elastic[1] + z * (elastic[2] + z * elastic[3]));
    }
    /// @brief Plateau at w past the puncture depth [N].
    double plateauN(double w) const noexcept { return plateau[0] + w * (plateau[1] + w * plateau[2]); }
};

} // namespace voxhap::haptic
