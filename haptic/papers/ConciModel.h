// SPDX-License-Identifier: Apache-2.0
/// @file ConciModel.h
/// @brief Conci et al. multi-layer polynomial (physics.md §3): elastic stage
/// Ce0 + Ce1·u + Ce2·u² (+ Ce3·u³) until S_f,max or the next tissue, a drop of
/// T_f at puncture, then the plastic plateau Cp0; u is the depth inside the
/// layer [chosen]. The constants are fitted from the [C-ui] seed data by the
/// procedure of §3.2, with BMI scaling and tip type of §3.3.
#pragma once

#include "haptic/Needle.h"

#include <string>
#include <vector>

namespace voxhap::haptic {

/// @brief [C-ui] seed row: total force at puncture and thickness.
struct ConciSeed {
    std::string name;
    double punctureForceN = 0;   ///< P_i [N]
    double thicknessMm = 0;      ///< Z_t [mm]
    bool depthTriggered = false; ///< punctured at the layer's end (flavum, epidural/dura), §3.2 step 2
    bool scalesWithBmi = true;   ///< §3.3: the epidural space and dura are not scaled [chosen]
};

/// @brief The [C-ui] table of physics.md §3.2, skin to epidural/dura (bone excluded: contact).
const std::vector<ConciSeed>& conciSeeds();
/// @brief The bone row's puncture force [N], the P_{i+1} of the last layer's plateau.
inline constexpr double kConciBonePunctureN = 8.0265;

/// @brief The slope multiplier of a needle tip shape (physics.md §3.3 [chosen, calibrate]).
double tipSlopeMultiplier(TipType tip);

/// @brief A fitted layer (physics.md §3.2 "Fitted table").
struct ConciLayer {
    std::string name;
    double zStartMm = 0, thicknessMm = 0, punctureDepthMm = 0; ///< z_start, Z_t, u_p [mm]
    double ce0 = 0, ce1 = 0, ce2 = 0, ce3 = 0;                 ///< [N], [N/mm], [N/mm²], [N/mm³]
    double sfMaxN = 0;                                         ///< S_f,max: elastic force at puncture [N]
    double tfN = 0;                                            ///< T_f: drop at puncture [N]
    double cp0 = 0, cp1 = 0, cp2 = 0;                          ///< plastic stage [N], [N/mm], [N/mm²]
};

/// @brief Fit the layers (§3.2 steps 1–4), thicknesses scaled by @p scale where the
/// seed allows (§3.3), elastic slopes multiplied by the tip's factor.
std::vector<ConciLayer> fitConci(const std::vector<ConciSeed>& seeds, double scale = 1.0, TipType tip = TipType::Coned,
    double nextPunctureN = kConciBonePunctureN);

/// @brief §3.3: scale s = SED/40.9 mm with SED = 2.52 + 0.11·BMI cm.
double conciBmiScale(double bmi);

/// @brief Layered insertion state: which layers are punctured, and the force.
/// @note Not thread-safe; the update is noexcept and does not allocate.
class ConciModel {
public:
    explicit ConciModel(std::vector<ConciLayer> layers);

    struct Output {
        double forceN = 0;      ///< resistance along the axis [N], >= 0
        int layer = -1;         ///< index of the layer at the tip, -1 outside
        bool punctured = false; ///< this update punctured a layer ("pop")
    };
    /// @brief Advance (or retract) the tip to depth @p zMm from first skin contact.
    Output update(double zMm) noexcept;
    void reset() noexcept;
    const std::vector<ConciLayer>& layers() const { return mLayers; }

private:
    std::vector<ConciLayer> mLayers;
    std::vector<char> mPunctured;
};

} // namespace voxhap::haptic
