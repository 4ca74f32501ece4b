// SPDX-License-Identifier: Apache-2.0
/// @file Guidance.h
/// @brief Guidance for novice mode: a virtual fixture that pulls
/// the needle tip toward the planned line, before the skin toward the line's
/// continuation through the planned entry (so the tip is led onto the entry), and
/// once in toward the line itself.
///
/// The force is perpendicular to the line only, f(r)·(−r̂) with r the tip's
/// distance from it: it never pushes along the line. An axial term would insert
/// or withdraw the needle for the trainee and would add to, or mask, the axial
/// resistance profile (tenting, pops, the loss of resistance) that the trainee is
/// there to learn; before the skin it would press the tip into the skin at the
/// entry. The depth stays the trainee's.
///
/// Profile [chosen]: f(r) = min(k·r, F_max), tapered to zero between the capture
/// radius R and 2R when R > 0 (a trainee who chose another line is not dragged
/// back), times a gain that fades out linearly from 1 to 0 over fadeOutS from the
/// first tick (0: no fade). Passivity (physics.md §6.1, §6.4): f depends on r
/// alone, so the field is the gradient of Φ(r) = ∫₀ʳ f and does no net work round
/// a closed loop; the sampled field leaks at most ½·K·Δx² a tick with K =
/// max(k, F_max/R); a gain that only falls only takes energy out. On the line
/// (r = 0) the force is exactly zero.
#pragma once

#include "core/Math.h"

namespace voxhap::haptic {

/// @brief The planned line: entry on the skin and target [mm, LPS].
struct GuideLine {
    Vec3d entry{0, 0, 0};
    Vec3d target{0, 0, 1};
};

/// @brief Guidance parameters (scene block `terms.guidance`, docs/scenes.md).
struct GuidanceParams {
    double stiffnessNPerMm = 0.2; ///< k, within the device's stable stiffness (§6.1) [chosen]
    double maxForceN = 1.0;       ///< F_max, under a Touch-class continuous limit (0.88 N) plus margin [chosen]
    double captureRadiusMm = 0.0; ///< R: taper from R to 2R; 0: everywhere [mm]
    double fadeOutS = 0.0;        ///< gain from 1 to 0 over this time from the first tick; 0: none [s]
};

/// @brief The guidance force on the tip.
/// @note One per force model; not thread-safe (the servo thread's own).
class Guidance {
public:
    /// @throw ValueError on a degenerate line or parameters out of range
    Guidance(const GuidanceParams& params, const GuideLine& line);

    /// @brief The force on the tip at @p tip [mm] and time @p timeS [s]; never
    /// allocates or throws. The first call after reset() starts the fade-out clock.
    Vec3d update(const Vec3d& tip, double timeS) noexcept;
    void reset() noexcept { mStarted = false; }

    /// @brief f(r) without the fade-out gain [N].
    double profileN(double rMm) const noexcept;
    /// @brief The tip's offset from the line, perpendicular to it [mm].
    Vec3d offset(const Vec3d& tip) const noexcept;
    /// @brief The fade-out gain at @p timeS (1 before the first tick).
    double gain(double timeS) const noexcept;
    const GuideLine& line() const noexcept { return mLine; }
    const GuidanceParams& params() const noexcept { return mP; }
    const Vec3d& direction() const noexcept { return mW; }
    /// @brief The steepest slope of the field, K above [N/mm].
    double stiffestNPerMm() const noexcept;

private:
    GuidanceParams mP;
    GuideLine mLine;
    Vec3d mW{0, 0, 1};
    double mStartS = 0.0;
    bool mStarted = false;
};

} // namespace voxhap::haptic
