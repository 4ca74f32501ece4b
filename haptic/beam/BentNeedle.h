// SPDX-License-Identifier: Apache-2.0
/// @file BentNeedle.h
/// @brief A needle that bends (physics.md §9): the quasi-static Euler–Bernoulli
/// beam from the hub, clamped to the device's pose, to the free tip; the tissue
/// as a Winkler foundation over the inserted length, resting on the track the tip
/// has cut; the bevel's lateral force at the tip; the shaft as a polyline.
///
/// One update() per servo tick: the assembly is O(n) in the nodes and the band
/// solve O(n); nothing allocates (every buffer is sized for the needle's length
/// at construction), nothing throws.
///
/// The state between ticks is the cut track (CutTrack.h), in the tissue's rest
/// frame: the tissue rests on it and on its straight continuation ahead of the
/// cut front, so uncut tissue holds the tip from the first millimetre. The beam
/// is solved afresh from the track and the hub's pose, so a hand that moves the
/// hub loads the shaft against the track; then the front advances along the tip's
/// heading by what the tip advanced (the tip cuts where it points, Webster et al.
/// 2006), so the path converges as the step shrinks (§9.3). Small-slope theory,
/// in the hub's frame: the deflection w(x) is lateral to the hub's axis, x along it.
#pragma once

#include "haptic/Needle.h"
#include "haptic/beam/CutTrack.h"
#include "haptic/beam/Foundation.h"
#include "haptic/beam/WinklerBeam.h"

#include <cmath>
#include <memory>
#include <span>
#include <vector>

namespace voxhap::haptic {

/// @brief The beam's constants, from the needle (physics.md §9.1–§9.4).
struct BeamParams {
    double lengthMm = 90.0;        ///< hub to tip [mm]
    double eiNmm2 = 0.0;           ///< bending stiffness E·I [N·mm²]
    double bevelFactorMm2 = 0.0;   ///< lateral tip force per unit modulus: P = k·factor [mm²] (0: symmetric tip)
    double bevelLengthMm = 0.0;    ///< the bevel face's axial length D·cot α [mm]
    double orientationRad = 0.0;   ///< bevel orientation about the shaft, from the reference axis
    double minNodeSpacingMm = 1.0; ///< at least this much needle per element [chosen]
    int maxNodes = 150;            ///< [chosen]: the solve's cost bound
    double trackStepMm = 0.25;     ///< arc length between track points [chosen]

    /// @brief From a needle: EI of its tube (and stylet), its bevel (§9.3).
    /// @throw ValueError naming the needle's field for a non-positive E, an ID not
    /// below the OD, or a bevel angle outside (0°, 90°)
    static BeamParams fromNeedle(const Needle& n);
};

/// @brief The lateral axis of bevel orientation 0 for a path along @p pathDirection:
/// the patient's superior direction (+z, LPS) across the path; left (+x) for a
/// path within 25° of the body's long axis (physics.md §9.3).
Vec3d bevelReferenceAxis(const Vec3d& pathDirection) noexcept;

class BentNeedle {
public:
    /// The steepest slope [rad] of the shaft to the hub's axis the small-slope
    /// theory is followed to; a steeper solution is scaled down to it (§9.4) [chosen:
    /// θ²/2, the theory's error, reaches 12 % there].
    static constexpr double kMaxSlope = 0.5;

    /// @param foundation the tissue's modulus (owned)
    /// @param referenceAxis the lateral direction of bevel orientation 0, taken ⟂
    ///        to the shaft each tick (a direction along the shaft falls back to another axis)
    /// @throw ValueError on bad parameters or a null foundation
    BentNeedle(const BeamParams& params, std::unique_ptr<Foundation> foundation, const Vec3d& referenceAxis);
    /// @brief A copy in the same state, with its own copy of the foundation (the
    /// planner branches a needle at a depth to try a turn there). Allocates.
    BentNeedle(const BentNeedle& o);
    BentNeedle& operator=(const BentNeedle&) = delete;
    BentNeedle(BentNeedle&&) noexcept = default;

    /// @brief No track, a straight needle.
    void reset() noexcept;
    /// @brief The tip has entered the skin at @p entry: the track starts there.
    void enter(const Vec3d& entry) noexcept;
    /// @brief The needle has left the tissue: the track is gone.
    void withdraw() noexcept { reset(); }
    bool entered() const noexcept { return !mTrack.empty(); }
    /// @brief The needle's roll about its axis [rad]: the bevel turns with it (a
    /// half turn flips it, physics.md §9.3).
    void setRoll(double rollRad) noexcept { mRoll = std::isfinite(rollRad) ? rollRad : mRoll; }
    /// @brief Bone holds the tip at @p at [mm, LPS] (physics.md §9.5): from the next
    /// update() the beam's tip node is pinned there across the shaft, the bevel cuts
    /// nothing and presses on nothing, and the track does not grow. A non-finite
    /// point is ignored.
    void pinTip(const Vec3d& at) noexcept;
    /// @brief The tip is free again (contact with the bone ended).
    void releaseTip() noexcept { mPinned = false; }
    bool tipPinned() const noexcept { return mPinned; }

    /// @brief Solve for the hub at @p hub, the shaft leaving it along @p direction.
    /// @return false (and a straight needle) on a non-finite pose or a failed solve.
    bool update(const Vec3d& hub, const Vec3d& direction) noexcept;

    /// @brief The shaft from the hub to the tip: the beam's nodes [mm, LPS].
    std::span<const Vec3d> shaft() const noexcept { return {mNodes.data(), mNodes.size()}; }
    const Vec3d& tip() const noexcept { return mNodes.back(); }
    const Vec3d& tipDirection() const noexcept { return mTipDirection; }
    /// @brief Length of needle below the skin [mm].
    double insertedMm() const noexcept { return mInserted; }
    /// @brief The bevel's lateral force on the tip this tick [N] (world).
    const Vec3d& bevelForce() const noexcept { return mBevelForce; }
    /// @brief The lateral force [N] and torque [N·mm] the needle puts on the hand at
    /// the hub: the clamp's reaction, reversed (physics.md §9.5).
    const Vec3d& hubForce() const noexcept { return mHubForce; }
    const Vec3d& hubTorque() const noexcept { return mHubTorque; }
    /// @brief The hub's lateral stiffness this tick [N/mm]: the force per mm the hub
    /// is moved sideways with the track held (§9.5; zero before the needle enters).
    double hubStiffnessNPerMm() const noexcept { return mHubStiffness; }
    /// @brief Lateral offset of the tip from the hub's axis [mm].
    double tipDeflectionMm() const noexcept;
    /// @brief This tick's solution was steeper than kMaxSlope and held there.
    bool slopeLimited() const noexcept { return mScale < 1.0; }
    const CutTrack& track() const noexcept { return mTrack; }
    const BeamParams& params() const noexcept { return mParams; }
    const WinklerBeam& beam() const noexcept { return mBeam; }
    int nodes() const noexcept { return int(mNodes.size()); }

private:
    void straight() noexcept;
    void extendTrack(double tipTau) noexcept;

    BeamParams mParams;
    WinklerBeam mBeam;
    CutTrack mTrack;
    std::unique_ptr<Foundation> mFoundation;
    Vec3d mReference;
    double mRoll = 0.0;
    // This tick's frame: hub, axis and the lateral pair.
    Vec3d mHub{0, 0, 0}, mU{0, 0, 1}, mE1{1, 0, 0}, mE2{0, 1, 0};
    std::vector<Vec3d> mNodes;
    std::vector<double> mAxial; ///< each node's distance along the axis (the bent shaft is shorter) [mm]
    Vec3d mTipDirection{0, 0, 1};
    Vec3d mBevelForce{0, 0, 0}, mHubForce{0, 0, 0}, mHubTorque{0, 0, 0};
    double mInserted = 0.0;
    double mHubStiffness = 0.0;
    double mScale = 1.0;        ///< this tick's solution, scaled to kMaxSlope when steeper
    double mBevelModulus = 0.0; ///< k the bevel presses on: the tissue at the tip (0 in bone)
    double mAheadModulus = 0.0; ///< k of the uncut tissue at the tip
    bool mPinned = false;       ///< bone holds the tip at mPin
    Vec3d mPin{0, 0, 0};
    Vec3d mLastHeading{0, 0, 1}; ///< the tip's direction at the last solve: where the next cut's heading starts
};

} // namespace voxhap::haptic
