// SPDX-License-Identifier: Apache-2.0
/// @file ForcePrediction.h
/// @brief The force a scene's model predicts along a path at a constant
/// insertion speed, without running the servo loop: the quasi-static reading of
/// the same terms (haptic/force/NeedleForceModel.cpp) at steady advance.
///
/// At steady speed v the stick-slip proxy slips (physics.md §6.2), so its force is
/// its threshold; the model's own layer state machine (haptic::InsertionState)
/// walks the layers. At tip depth d the axial resistance is
///
///     F(d) = E(d)                      elastic stage of a tenting layer (§2.1 Eq. 4, §3.1, §4 Eq. 2)
///          + Σ cutting + P(w) + C      nested-box cutting, plateau, Coulomb (§2.1 Eq. 3, §3.1, §4 Eq. 3)
///          + v·Σ b_i·l_i               shaft viscous friction (§4 Eq. 3)
///          + D(d)                      voxel damping, capped (§1.2 Eq. 5, §1.1 cap, §6.2 split)
///
/// with D = min(min(B, b_dev)·v, cap) + clamp((B − b_dev)·v_ref, 0, cap − ·), B = ∫β ds
/// over the shaft: the last needle-length of the path, clipped at the entry, which is
/// taken to lie on the skin (nothing but air behind it). While the shaft touches a
/// critical structure the model renders zero (§1.1), and so does the prediction.
/// The profile stops where the tip meets a rigid layer: bone is contact at the
/// device's stiffness (§1.3), whose force depends on the user's push, not the path.
#pragma once

#include "haptic/Layer.h"
#include "haptic/force/NeedleForceModel.h"
#include "haptic/shaft/LabelTrace.h"
#include "planning/Trajectory.h"

#include <vector>

namespace voxhap::planning {

/// @brief ∫β ds along a traced line from its damping pieces: prefix sums, O(log n) per query.
class DampingLine {
public:
    DampingLine() = default;
    /// @param pieces in order along the line, not overlapping (LabelTracer's output)
    explicit DampingLine(std::vector<haptic::DampingPiece> pieces);
    /// @brief ∫β ds over [a, b] [N·s/mm].
    double integral(double a, double b) const { return to(b) - to(a); }

private:
    double to(double x) const;
    std::vector<haptic::DampingPiece> mPieces;
    std::vector<double> mBefore; ///< ∫β up to each piece's start
};

struct ForceModelInputs {
    const std::vector<haptic::Layer>* layers = nullptr; ///< along the path, depths from the entry
    haptic::ForceTerms terms;
    haptic::Needle needle;
    haptic::DeviceLimits device;
    double speedMmPerS = 10.0;
    double stepMm = 1.0;
    const DampingLine* damping = nullptr; ///< β along the path (when terms.damping.on)
};

struct ForceProfile {
    std::vector<ForceSample> samples;
    double peakN = 0, peakDepthMm = 0;
    double contactMm = kNoDepth; ///< first rigid layer met
};

/// @brief Predict F(d) for d from 0 (the entry) to @p lengthMm, or the first rigid contact.
ForceProfile predictForce(const ForceModelInputs& in, double lengthMm);

} // namespace voxhap::planning
