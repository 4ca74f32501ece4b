// SPDX-License-Identifier: Apache-2.0
/// @file MaterialField.h
/// @brief The mapping layer: a Volume's image values turned into the mechanical
/// properties the force models read (architecture.md "Data flow").
///
/// Only what a scene needs is built: the damping grid for tissue damping, the
/// bone-stiffness grid for bone contact; per-label parameters are a small table.
/// Air (label 0) stays inactive in every grid. Typed grid access lives in
/// haptic/materials/FieldGrids.h (OpenVDB headers).
#pragma once

#include "haptic/DeviceLimits.h"
#include "haptic/materials/MaterialLaws.h"
#include "volume/TissueTable.h"
#include "volume/Volume.h"

#include <array>
#include <cstdint>
#include <optional>

namespace voxhap::haptic {

/// @brief Labels the force path can index: tissue ids 0..kMaxLabels-1.
inline constexpr int kMaxLabels = 64;

/// @brief Which property grids to build.
struct MaterialNeeds {
    bool damping = true;        ///< β grid (Kyung Eq. 5, physics.md §1.2)
    bool boneStiffness = false; ///< contact stiffness grid (physics.md §1.3)
};

/// @brief How image values map to mechanics.
struct MaterialOptions {
    MaterialNeeds needs;
    /// T1 law of this field strength (physics.md §5.4); by default the volume's
    /// VolumeMetadata::fieldStrength, else 1.5 T when the metadata record none.
    /// A field they record as neither 1.5 T nor 3 T has no law: T1 is not read,
    /// and damping comes from the labels alone (refused without labels).
    std::optional<volume::FieldStrength> field;
    ModulusLaw modulusLaw = ModulusLaw::Kopperdahl2002; ///< QCT density, as HU gives (§5.3)
    double tipAreaMm2 = 1.27;                           ///< needle tip area [mm²]: 18 G (physics.md §1.3)
    DeviceLimits device;                                ///< bone stiffness is limited to what it renders
};

/// @brief Per-label parameters from the tissue table, in canonical units; zero where absent.
struct LabelMaterial {
    bool present = false;               ///< the table has this id
    bool critical = false;              ///< touching it zeroes the force (physics.md §1.1)
    bool rigid = false;                 ///< bone: contact, not cutting (§1.3)
    double dampingNsPerMm2 = 0;         ///< β [N·s/mm²]
    double punctureForceN = 0;          ///< [N]
    double cuttingForceN = 0;           ///< [N]
    double elasticityNPerMm = 0;        ///< [N/mm]
    double frictionViscousNsPerMm2 = 0; ///< b [N·s/mm²]
    double frictionCoulombN = 0;        ///< C [N]
    double foundationNPerMm2 = 0;       ///< Winkler modulus k holding a bending needle [N/mm²] (§9.2)
};

/// @brief Bone stiffness as computed from HU, and as rendered.
struct StiffnessReport {
    std::int64_t boneVoxels = 0;
    double computedMaxNPerMm = 0; ///< k = E(ρ(HU))·A/L_c before limiting
    double computedMeanNPerMm = 0;
    double renderedMaxNPerMm = 0; ///< after limiting to the device
    double deviceLimitNPerMm = 0;
};

/// @brief Where the damping of the body came from (physics.md §5.5): T1 through
/// Eq. 4 (fat and muscle where the t1 grid is active), or the table by label.
struct DampingSources {
    std::int64_t fromT1Voxels = 0;
    std::int64_t fromTableVoxels = 0;
    /// The fraction of the body's voxels whose β came from T1 (0 for an empty body).
    double t1Fraction() const
    {
        const std::int64_t n = fromT1Voxels + fromTableVoxels;
        return n ? double(fromT1Voxels) / double(n) : 0.0;
    }
};

/// @brief Mechanical property grids and per-label parameters of one volume.
/// @note Immutable after construction; share it between threads freely.
class MaterialField {
public:
    using GridConstPtr = volume::Volume::GridConstPtr;

    /// @brief Build from a volume: β from T1 for fat and muscle (§5.4, T1 clamped),
    /// per-label β otherwise; bone stiffness from HU (§5.3, §1.3).
    /// @throw ValueError if a needed input grid is missing or labels exceed kMaxLabels-1
    MaterialField(const volume::Volume& v, const volume::TissueTable& table, const MaterialOptions& options);

    /// @brief Assemble from ready grids (tests and benchmarks): @p beta a FloatGrid
    /// [N·s/mm²] (may be null), @p labels an Int32Grid (may be null), sharing a transform.
    MaterialField(GridConstPtr beta, GridConstPtr labels, const volume::TissueTable& table);

    GridConstPtr damping() const { return mBeta; }            ///< FloatGrid β [N·s/mm²], or null
    GridConstPtr labels() const { return mLabels; }           ///< Int32Grid tissue ids, or null
    GridConstPtr boneStiffness() const { return mStiffness; } ///< FloatGrid k [N/mm], device-limited, or null
    const std::array<LabelMaterial, kMaxLabels>& perLabel() const { return mPerLabel; }
    const StiffnessReport& stiffnessReport() const { return mStiffnessReport; }
    /// @brief The T1 law used for β (meaningful when a t1 grid was used).
    const T1DampingLaw& t1Law() const { return mLaw; }
    /// @brief Largest β anywhere in the field [N·s/mm²] (for error bounds).
    double maxDamping() const { return mMaxBeta; }
    /// @brief Where β came from, voxel by voxel (zero when no damping grid was built).
    const DampingSources& dampingSources() const { return mSources; }

private:
    void fillPerLabel(const volume::TissueTable& table);

    GridConstPtr mBeta, mLabels, mStiffness;
    std::array<LabelMaterial, kMaxLabels> mPerLabel{};
    StiffnessReport mStiffnessReport;
    T1DampingLaw mLaw;
    double mMaxBeta = 0;
    DampingSources mSources;
};

} // namespace voxhap::haptic
