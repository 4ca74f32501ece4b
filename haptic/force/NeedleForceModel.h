// SPDX-License-Identifier: Apache-2.0
/// @file NeedleForceModel.h
/// @brief One servo tick: kinematics → insertion state → force terms → safety
/// (architecture.md "The force pipeline"). Each term is a small function of the
/// state and the materials; a term the scene does not name is not evaluated.
///
/// The needle moves along a path (origin, unit direction): depth d is the tip's
/// projection on it. Forces are on the needle, in world axes [N]; the axial
/// resistance is reported positive when it pushes the needle back out.
#pragma once

#include "haptic/DeviceLimits.h"
#include "haptic/Events.h"
#include "haptic/Needle.h"
#include "haptic/beam/BentNeedle.h"
#include "haptic/force/ContactTransient.h"
#include "haptic/force/Guidance.h"
#include "haptic/force/InsertionState.h"
#include "haptic/force/LorChannel.h"
#include "haptic/force/Palpation.h"
#include "haptic/force/PivotCorrection.h"
#include "haptic/force/Safety.h"
#include "haptic/force/StickSlipProxy.h"
#include "haptic/shaft/ShaftIntegration.h"

#include <limits>
#include <memory>
#include <optional>
#include <vector>

namespace voxhap::haptic {

/// @brief Which terms run, and their parameters (physics.md section beside each).
struct ForceTerms {
    bool tip = true;     ///< the layers' elastic stage and pops (§2.1 Eq. 4, §3.1, §4 Eq. 2)
    bool cutting = true; ///< nested-box cutting, plateau and Coulomb C through the proxy (§2.1 Eq. 3, §3.1, §4, §6.2)
    bool viscous = true;              ///< shaft friction b·v·l (§4 Eq. 3)
    double karnoppDeltaVMmPerS = 0.0; ///< C only while |v| >= Δv ([LP] Eq. 3); 0: always (the proxy sticks)
    double keepDirectionN = 0.0;      ///< [LP] f_keepdir for v <= 0 (device compensation, §4)
    struct Damping {
        bool on = false;   ///< Kyung Eq. 5 voxel damping (§1.2)
        double capN = 6.0; ///< |F_R| <= 6 N (§1.1)
        double referenceSpeedMmPerS =
            10.0; ///< damping beyond the device's is rendered as friction at this speed (§6.2) [K01: 1 cm/s]
    } damping;
    struct Bone {
        bool on = true;        ///< rigid layers are contact at the device's stiffness (§1.3)
        bool transient = true; ///< decaying-sine transient scaled by impact speed (§2.1 Eq. 2)
        ContactTransient params;
    } bone;
    struct Pivot {
        bool on = false; ///< layered Kelvin correction about the skin pivot (§1.4)
        PivotParams params;
    } pivot;
    struct Lock {
        bool on = false;              ///< [S19] trajectory lock after skin entry (§2.1, §6.2 virtual coupling)
        double stiffnessNPerMm = 0.0; ///< 0: the device's maximum stiffness
    } lock;
    struct Lor {
        bool on = false; ///< syringe plunger channel (§2.3)
        LorParams params;
    } lor;
    struct BoneTexture {
        bool on = false; ///< [LP] bone texture f = −c·sgn(v) while the tip is in bone (§4), through the proxy (§6.2)
        double cN = 0.3; ///< c [N]: not given in [LP]; 0.3 N [chosen, physics.md §4]
    } boneTexture;
    struct PalpationTerm {
        bool on = false; ///< the skin felt before the needle touches it (Palpation.h; §6.2 proxy)
        PalpationParams params;
    } palpation;
    struct GuidanceTerm {
        bool on = false; ///< virtual fixture toward the planned line (Guidance.h)
        GuidanceParams params;
    } guidance;
    struct Bending {
        bool on = false; ///< the needle bends (§9): a beam on the tissue, the bevel's force, the shaft a polyline
    } bending;
    bool critical = true;        ///< touching a critical structure zeroes the force (§1.1)
    double couplingNPerMm = 0.0; ///< stick-slip proxy stiffness; 0: the device's maximum stiffness (§6.2)
    /// Uniform scale on the force sent to the device (the scene's force_scale):
    /// every term alike (palpation and guidance too), so the contrasts between
    /// layers survive, while the device's I²t budget lasts to bone contact. The model's own figures (axialN,
    /// modelForce) stay unscaled; F_G is not scaled.
    double renderScale = 1.0;
};

/// @brief The device's reading at one tick.
struct NeedleInput {
    double timeS = 0;         ///< [s]
    double dtS = 0.001;       ///< since the last tick [s]
    Vec3d tip{0, 0, 0};       ///< [mm, LPS]
    Vec3d direction{0, 0, 1}; ///< shaft direction, hub to tip (normalised here)
    Vec3d velocity{0, 0, 0};  ///< tip velocity [mm/s]
    /// The needle's roll about its axis [rad], NaN when the device senses none: a
    /// bending needle's bevel turns with it (physics.md §9.3); without a roll it
    /// keeps the scene's bevel orientation and the last roll read.
    double rollRad = std::numeric_limits<double>::quiet_NaN();
};

/// @brief Each term's axial share [N] (positive pushes out) and the lateral terms.
struct ForceBreakdown {
    double elastic = 0, proxy = 0, viscous = 0, damping = 0, bone = 0, transient = 0, keepDirection = 0;
    Vec3d lateral{0, 0, 0};   ///< pivot correction, lock and bone sticking [N]
    Vec3d gravity{0, 0, 0};   ///< Kyung's F_G = −m·g holding up the handle (§1.1 Eq. 1) [N]
    Vec3d palpation{0, 0, 0}; ///< the skin's push on the palpating tip [N]
    Vec3d guidance{0, 0, 0};  ///< the guidance fixture's pull toward the planned line [N]
    /// A bending needle's lateral force at the hub through the virtual coupling (§9.5) [N]
    Vec3d bending{0, 0, 0};
};

struct NeedleOutput {
    Vec3d force{0, 0, 0};      ///< rendered, after safety [N]
    Vec3d modelForce{0, 0, 0}; ///< the model's F_R + F_C + F_G (§1.1 Eq. 1), before the render scale and safety [N]
    /// How much the device's peak and I²t limits cut from the scaled demand this
    /// tick [N] (0: not limited). A tick where this turns positive raises a
    /// ForceLimited event.
    double limitedN = 0;
    double axialN = 0; ///< model resistance along the path [N], + outward
    ForceBreakdown terms;
    double plungerN = 0;    ///< syringe plunger force [N]
    double speedMmPerS = 0; ///< along the path [mm/s]
    TipState tip;
    /// A bending needle's torque at the hub [N·mm] (§9.5): recorded for a device
    /// with a torque channel; none of the presets has one, so it is not rendered.
    Vec3d hubTorque{0, 0, 0};
    bool critical = false; ///< force zeroed by a critical structure
    bool fault = false;    ///< latched safety fault
    /// Palpating: the tip is felt against the skin map, not yet a needle on its
    /// path (the layer model waits; Palpation.h). Only with the palpation term.
    bool palpating = false;
    PalpationOutput palpation; ///< the proxy's state while palpating
    EventBuffer events;        ///< this tick's events
};

/// @brief The needle's path: where depth 0 is, and the insertion direction.
struct NeedlePath {
    Vec3d origin{0, 0, 0};
    Vec3d direction{0, 0, 1};
};

/// @brief The Coulomb-type resistance at the tip, the stick-slip proxy's slip
/// force before damping: nested-box cutting (§2.1 Eq. 3), the plateau past a
/// puncture (§3.1) and the layer's C while |v| >= Δv (§4 Eq. 3). Shared by the
/// servo model and the planner's prediction; noexcept, no allocation.
double tipSlipForceN(const ForceTerms& terms, const TipState& tip, const std::vector<Layer>& layers, double v) noexcept;

/// @brief The tip is in bone: on a rigid layer (contact, §1.3) or inside a layer
/// whose role is bone (the [LP] table's elastic bone row, §4).
bool tipInBone(const TipState& tip, const std::vector<Layer>& layers) noexcept;

/// @brief Kyung's voxel damping (§1.2 Eq. 5) for damping integral @p b
/// [N·s/mm] at speed @p v: what the device can render as viscous force, the
/// rest as friction at the reference speed (§6.2), both within the cap (§1.1).
struct DampingSplit {
    double viscousN = 0.0, frictionN = 0.0;
};
DampingSplit splitDamping(const ForceTerms::Damping& damping, const DeviceLimits& device, double b, double v) noexcept;

/// @brief Everything a force model is built from (the scene builds it from a
/// scene file: Scene.h; tests and embedding code fill it by hand).
struct ForceModelSetup {
    std::vector<Layer> layers; ///< the layers along the path (LayerTables.h)
    NeedlePath path;
    ForceTerms terms;
    Needle needle;
    DeviceLimits device;
    /// Shaft integrator over the scene's material field, or null when no term
    /// reads voxels (damping, or critical structures off the path).
    std::unique_ptr<ShaftIntegrator> integrator;
    /// The material field behind @p integrator (per-label flags), or null.
    const MaterialField* field = nullptr;
    /// An integrator used once the skin is entered and the needle is tied to its
    /// line (a TrajectoryProfile: O(1) per tick), or null to keep @p integrator.
    std::unique_ptr<ShaftIntegrator> locked;
    /// The skin map palpation reads (SceneInstance builds it), or null; required
    /// with terms.palpation.on.
    std::shared_ptr<const SkinMap> skin;
    /// The planned line guidance pulls toward; with terms.guidance.on and none
    /// given, the path itself.
    std::optional<GuideLine> guide;
    /// The tissue holding a bending needle (BentNeedle.h); required with terms.bending.on.
    std::unique_ptr<Foundation> foundation;
};

class NeedleForceModel {
public:
    /// @throw ValueError on a degenerate path, damping without an integrator,
    /// palpation without a skin map, a degenerate guide line, or bending without a
    /// foundation or beside the lock or the pivot correction
    explicit NeedleForceModel(ForceModelSetup setup);

    /// @brief One tick. Never allocates, locks or throws.
    void step(const NeedleInput& in, NeedleOutput& out) noexcept;
    void reset() noexcept;

    const std::vector<Layer>& layers() const { return mState.layers(); }
    const InsertionState& state() const { return mState; }
    const NeedlePath& path() const { return mPath; }
    const ForceTerms& terms() const { return mTerms; }
    const Needle& needle() const { return mNeedle; }
    const DeviceLimits& device() const { return mDevice; }
    const Safety& safety() const { return mSafety; }
    /// @brief The palpation contact, when the term is on.
    const PalpationContact* palpation() const { return mPalp ? &*mPalp : nullptr; }
    /// @brief The guidance fixture, when the term is on.
    const Guidance* guidance() const { return mGuide ? &*mGuide : nullptr; }
    /// @brief The bending needle (physics.md §9), when the term is on.
    const BentNeedle* bentNeedle() const { return mBeam.get(); }
    BentNeedle* bentNeedle() { return mBeam.get(); }

private:
    bool touchingCritical() const noexcept;
    /// The needle on its path: insertion state and the layer terms (steps 2 and 3).
    void needleTerms(const NeedleInput& in, double t, double dt, double d, double v, const Vec3d& dir, const Vec3d& hub,
        NeedleOutput& out) noexcept;
    /// Skin entry starts the bending needle's track, withdrawal ends it (§9.3).
    void bendingEvent(const Event& e, const Vec3d& tip, double d, const Vec3d& dir) noexcept;

    InsertionState mState;
    NeedlePath mPath;
    ForceTerms mTerms;
    Needle mNeedle;
    DeviceLimits mDevice;
    std::unique_ptr<ShaftIntegrator> mIntegrator, mLocked;
    const MaterialField* mField = nullptr;
    ShaftIntegral mIntegral;
    StickSlipProxy mProxy;
    LorChannel mLor;
    PivotCorrection mPivot;
    Safety mSafety;
    // Bone contact: where and when the tip met it, and how fast.
    Vec3d mContactPoint{0, 0, 0};
    double mContactTimeS = 0, mImpactMmPerS = 0;
    bool mInContact = false;
    /// Trajectory lock: the tip's offset from the path where it entered the skin (§2.1).
    Vec3d mLockAnchor{0, 0, 0};
    Vec3d mGravity{0, 0, 0}; ///< F_G = −m·g (§1.1), constant
    bool mCritical = false;
    bool mLimited = false; ///< the device limits cut the last tick's demand
    std::optional<PalpationContact> mPalp;
    std::optional<Guidance> mGuide;
    std::unique_ptr<BentNeedle> mBeam; ///< with terms.bending.on (§9)
    bool mPalpating = false;           ///< palpation mode (switched only while out of contact)
    int mLastDirection = 1;
    double mLastTimeS = 0;
};

} // namespace voxhap::haptic
