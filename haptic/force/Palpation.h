// SPDX-License-Identifier: Apache-2.0
/// @file Palpation.h
/// @brief Palpation before insertion: the patient's back as a
/// surface the device touches before the needle touches the skin, so that the
/// spinous processes and the interspaces between them are felt and the entry can
/// be found by touch ([LP] and [C-ui] name palpation as the first step).
///
/// Two parts:
/// - SkinMap (set-up, allocates): the skin seen along the insertion direction,
///   sampled on a square grid across it, from the volume's labels (the first
///   tissue, the first rigid tissue) or from HU (thresholds of physics.md §5.2);
///   per node the skin depth, the soft-tissue thickness T over bone, and the
///   contact stiffness and friction that follow from T.
/// - PalpationContact (servo path: noexcept, no allocation): a god-object proxy
///   (Zilles & Salisbury 1995; the virtual coupling of physics.md §6.2) that stays
///   outside the skin and pulls the tip back to it with the stiffness at the proxy.
///
/// Stiffness [chosen]: the soft tissue over bone as a compressed layer of modulus
/// E under a fingertip of area A, k(T) = E·A/T, clamped to [k_min, k_max] (k_max
/// the device's stable stiffness, §6.1, §6.3): thin tissue over a spinous process
/// is stiff, the interspace and the paraspinal muscle are soft. Texture: Coulomb
/// friction at the proxy, coefficient μ rising from μ_soft to μ_bone as k goes
/// from k_min to k_max (the [LP] bone texture −c·sgn(v), physics.md §4, felt
/// through the skin).
///
/// Passivity (physics.md §6.1, §6.4): the proxy X minimises, or at least never
/// raises, the coupling energy G(X, p) = ½·k(X)·|X − p|² over the points outside
/// the skin; the force is −∂G/∂p = k(X)·(X − p). With the proxy held, G is a
/// quadratic in the tip position p, so the work the force does on the hand over a
/// tick is at most the fall of G plus ½·k·Δp², the sampled spring's own leak;
/// moving the proxy only ever lowers G. Round any closed loop that starts and ends
/// out of contact the model therefore returns no more than Σ ½·k_max·Δp², however
/// the stiffness varies with the bone beneath (a spring whose stiffness merely
/// followed the tip would hand back ½·(k_bone − k_soft)·δ² per loop).
#pragma once

#include "core/Math.h"
#include "volume/TissueTable.h"
#include "volume/Volume.h"

#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace voxhap::haptic {

/// @brief Where the skin map reads the skin and the bone.
enum class SkinSource {
    Auto,   ///< labels when the volume has them, else HU
    Labels, ///< first non-air label; first rigid tissue (tissue table)
    Hu      ///< HU above skinHu; HU at or above boneHu
};

/// @brief Palpation parameters (scene block `terms.palpation`, docs/scenes.md).
struct PalpationParams {
    /// The needle takes over (the layer model of the path) when the tip, out of
    /// contact, is within this lateral distance of the path [mm] [chosen: a
    /// fingertip's half width].
    double entryRadiusMm = 3.0;
    double modulusKPa = 30.0;         ///< E of the soft tissue in compression [kPa] [chosen]
    double contactAreaMm2 = 100.0;    ///< A, a fingertip pad [mm²] [chosen]
    double minStiffnessNPerMm = 0.02; ///< k_min, also where no bone is within reach [N/mm]
    double maxStiffnessNPerMm = 0.0;  ///< k_max; 0: the device's maximum stiffness [N/mm]
    double frictionSoft = 0.1;        ///< μ at k_min [chosen]
    double frictionBone = 0.5;        ///< μ at k_max [chosen]
    double radiusMm = 60.0;           ///< the map covers ±radius across the path, about the entry [mm]
    double aboveMm = 30.0;            ///< columns start this far outside the entry, along the path [mm]
    double reachMm = 100.0;           ///< bone is looked for this far below the skin [mm]
    double gridMm = 0.0;              ///< node spacing; 0: the volume's smallest voxel, at least 0.25 mm
    SkinSource source = SkinSource::Auto;
    double skinHu = -400.0; ///< air/tissue threshold: between air (−1000) and fat (−100) (§5.2) [HU]
    double boneHu = 150.0;  ///< bone threshold (§5.2) [HU]
};

/// @brief One place on the map: what lies beneath it.
struct SkinSample {
    bool surface = false;          ///< the skin is there (else the column is free: no tissue)
    double skinMm = 0;             ///< depth of the skin along the path direction [mm]
    double gradA = 0, gradB = 0;   ///< ∂skin/∂a, ∂skin/∂b
    double stiffnessNPerMm = 0;    ///< k
    double gradKA = 0, gradKB = 0; ///< ∂k/∂a, ∂k/∂b [N/mm²]
    double friction = 0;           ///< μ
    double thicknessMm = std::numeric_limits<double>::infinity(); ///< T, infinite without bone in reach
};

/// @brief The skin across the insertion direction, with what lies beneath it.
/// Map coordinates (a, b, d): a and b across the path, d the depth along it from
/// the path's origin (the entry); the body lies at d > skin(a, b).
/// @note Immutable after construction; share it between threads freely.
class SkinMap {
public:
    /// @brief Cast one column per node along @p inward from @p origin − aboveMm·inward.
    /// @param k_max the device's stable stiffness, used when params.maxStiffnessNPerMm is 0
    /// @throw ValueError when the source is missing (labels asked, none), or no column meets skin
    SkinMap(const volume::Volume& volume, const volume::TissueTable& table, const Vec3d& origin, const Vec3d& inward,
        const PalpationParams& params, double deviceStiffnessNPerMm);

    /// @brief Bilinear in the four nodes around (a, b); a column with a free node
    /// is free. Outside the map the border nodes extend outward.
    SkinSample sample(double a, double b) const noexcept;
    Vec3d toMap(const Vec3d& world) const noexcept;
    Vec3d toWorld(const Vec3d& map) const noexcept;

    /// @brief Soft-tissue stiffness and friction for thickness @p T [mm] (the law above).
    double stiffnessFor(double thicknessMm) const noexcept;
    double frictionFor(double stiffnessNPerMm) const noexcept;
    double minStiffness() const noexcept { return mKMin; }
    double maxStiffness() const noexcept { return mKMax; }
    int nodes() const noexcept { return mN; }
    double gridMm() const noexcept { return mStep; }
    const Vec3d& origin() const noexcept { return mOrigin; }
    const Vec3d& inward() const noexcept { return mU; }
    bool fromLabels() const noexcept { return mFromLabels; }
    /// @brief Nodes whose column met the skin, and how many of those found bone.
    long skinNodes() const noexcept { return mSkinNodes; }
    long boneNodes() const noexcept { return mBoneNodes; }

private:
    struct Node {
        double skin = std::numeric_limits<double>::quiet_NaN(); ///< NaN: free column
        double thickness = std::numeric_limits<double>::infinity();
        double k = 0, mu = 0;
    };
    const Node& node(int i, int j) const noexcept { return mNodes[std::size_t(j) * std::size_t(mN) + std::size_t(i)]; }

    Vec3d mOrigin, mU, mE1, mE2;
    double mStep = 0.5, mHalf = 0;
    int mN = 0;
    double mEA = 0, mKMin = 0, mKMax = 0, mMuSoft = 0, mMuBone = 0;
    bool mFromLabels = false;
    long mSkinNodes = 0, mBoneNodes = 0;
    std::vector<Node> mNodes;
};

/// @brief The palpation force of one tick.
struct PalpationOutput {
    bool contact = false;       ///< the tip is below the skin: the proxy holds it back
    Vec3d force{0, 0, 0};       ///< on the tip, world [N]
    Vec3d proxy{0, 0, 0};       ///< the god-object, world [mm]
    double indentationMm = 0;   ///< |proxy − tip| [mm]
    double stiffnessNPerMm = 0; ///< k at the proxy
    double friction = 0;        ///< μ at the proxy
    double thicknessMm = std::numeric_limits<double>::infinity(); ///< T at the proxy [mm]
    double energyNmm = 0;                                         ///< G = ½·k·|X − p|² [N·mm]
};

/// @brief The god-object contact on a SkinMap (see the file comment).
/// @note One per force model; not thread-safe (the servo thread's own).
class PalpationContact {
public:
    explicit PalpationContact(std::shared_ptr<const SkinMap> map) noexcept : mMap(std::move(map)) { }

    /// @brief Is the world point @p tip below the skin (in contact)?
    bool inside(const Vec3d& tip) const noexcept;
    /// @brief Move the tip to @p tip [mm, world]; never allocates or throws.
    const PalpationOutput& update(const Vec3d& tip) noexcept;
    void reset() noexcept;
    const PalpationOutput& output() const noexcept { return mOut; }
    const SkinMap& map() const noexcept { return *mMap; }

private:
    double energy(const Vec3d& x, const Vec3d& p, SkinSample* at = nullptr) const noexcept;

    std::shared_ptr<const SkinMap> mMap;
    Vec3d mProxy{0, 0, 0}; ///< map coordinates
    bool mHave = false, mOnSurface = false;
    PalpationOutput mOut;
};

} // namespace voxhap::haptic
