// SPDX-License-Identifier: Apache-2.0
/// @file LayerTables.h
/// @brief The layers on a path, two ways:
/// - patient-specific: the label runs the voxels put on the path, each layer
///   taking its parameters from the tissue table by label;
/// - fixed table: the papers' own layer tables ([LP] Table I, Conci's fitted
///   table, [S19] Table I), for the regression tests.
/// A layer model (Sénac, Conci, lumbar puncture, Kyung) decides which of a
/// layer's parameters are filled, and from what.
#pragma once

#include "core/Math.h"
#include "haptic/Layer.h"
#include "haptic/materials/MaterialField.h"
#include "haptic/papers/ConciModel.h"
#include "haptic/shaft/LabelTrace.h"
#include "phantoms/Phantoms.h"
#include "volume/TissueTable.h"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::haptic {

/// @brief The layered models (physics.md §1–§4).
enum class LayerModel {
    Kyung,          ///< §1: no layer forces; voxel damping, bone contact and pivot correction only
    Senac,          ///< §2: tenting a1·z + a2·z² on named layers, nested-box cutting
    Conci,          ///< §3: elastic polynomial to S_f,max, drop T_f, plastic plateau
    LumbarPuncture, ///< §4: f_tip = −k·x per layer, viscous b·v·l, Coulomb C
};
LayerModel parseLayerModel(
    const std::string& name); ///< "kyung", "senac", "conci", "lumbar-puncture"; @throw ValueError
const char* layerModelName(LayerModel m);

/// @brief A scene's change to one tissue's parameters (canonical units).
struct TissueOverride {
    std::optional<double> punctureForceN, cuttingForceN, tentDepthMm, elasticityNPerMm;
};

/// @brief How layers get their parameters.
struct LayerRecipe {
    LayerModel model = LayerModel::Senac;
    /// The tissues with a tenting stage (§2.1 Eq. 4, §2.2 constants). Sénac: [S19]'s
    /// derma, and the dura, whose puncture force is Table I's F_dura. Kyung: only
    /// what the scene names ([K01] §1.1 deforms the skin before it gives way); the
    /// scene parser clears this default for a kyung scene without a "tenting" list.
    std::vector<std::string> tenting{"skin", "dura"};
    /// Sénac: push depth at puncture z_p [mm] where no override names one:
    /// z_p = F_p/(2·k) with k the tissue's elasticity, so that a1 = k [chosen].
    std::map<std::string, TissueOverride> overrides; ///< by tissue name
    double forceScale =
        1.0; ///< needle gauge factor d/d_ref on the tip's forces (Needle.h, §3.3): every model, both layer sources
    TipType tip = TipType::Coned; ///< Conci slope multiplier (§3.3)
};

/// @brief Conci from labels: the puncture force of a tissue the table gives none
/// (soft_tissue, an imported lesion) [N]. [C-ui]'s muscle row, 4.354 N (physics.md
/// §3.2): the generic soft tissue of the seed data [chosen].
inline constexpr double kConciDefaultPunctureN = 4.354;

/// @brief Layers from label runs: parameters from the tissue table by label. Conci:
/// a tissue without a puncture force takes kConciDefaultPunctureN; lumbar puncture:
/// a tissue without elasticity, viscosity or Coulomb friction has none (0).
/// @throw ValueError if a label is not in the table
std::vector<Layer> layersFromRuns(
    const std::vector<LabelRun>& runs, const volume::TissueTable& table, const LayerRecipe& recipe);

/// @brief The papers' tables, with the skin surface at depth 0:
/// - LumbarPuncture: [LP] Table I exactly (its "out of skin" row becomes air at −5..0 mm),
///   k and C scaled by the recipe's forceScale (1 at the reference gauge);
/// - Conci: the §3.2 fitted table, thicknesses scaled for @p bmi (§3.3) when given,
///   forces by the recipe's forceScale;
/// - Senac: [S19] Table I for @p preset (derma and epidural lengths, F_dura) with the
///   tissue table's other thicknesses and forces (the lumbar phantom's layout);
/// - Kyung: none (the model reads voxels): throws.
std::vector<Layer> fixedLayers(const LayerRecipe& recipe, const volume::TissueTable& table,
    volume::LumbarPreset preset = volume::LumbarPreset::Average, std::optional<double> bmi = std::nullopt);

/// @brief Syringe plunger resistance of a role [chosen, physics.md §2.3]: blocked (1)
/// in skin, ligament, dura and bone; 0.3 in other soft tissue; 0.05 in the epidural
/// space; free (0) in CSF and air.
double lorResistance(LayerRole role);

} // namespace voxhap::haptic
