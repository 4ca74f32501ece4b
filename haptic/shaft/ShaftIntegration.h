// SPDX-License-Identifier: Apache-2.0
/// @file ShaftIntegration.h
/// @brief Material integrals along the needle shaft: ∫β ds, the length spent
/// in each label and the first hit of each label, with interchangeable
/// strategies (architecture.md "Shaft integration"; physics.md §1.2, §7).
///
/// A shaft is the segment from the entry point to the tip, in world mm, or a
/// polyline when the needle bends (physics.md §9.5). Two
/// readings of a voxel field are integrated exactly:
/// - piecewise constant: each voxel's value fills its cell (Kyung's Σ b_k,
///   chord-weighted); the exact traversal is exact for it;
/// - trilinear: values at voxel centres, trilinear in between; the exact
///   trilinear traversal integrates it with no discretisation error.
/// Labels are categorical: lengths and first hits always use the voxel cells.
#pragma once

#include "core/Math.h"
#include "haptic/materials/MaterialField.h"

#include <array>
#include <limits>
#include <memory>
#include <span>
#include <string>

namespace voxhap::haptic {

/// @brief A needle shaft: from the entry point to the tip [mm, LPS].
struct Segment {
    Vec3d entry{0, 0, 0};
    Vec3d tip{0, 0, 0};
};

/// @brief firstHitMm of a label the shaft does not meet.
inline constexpr double kNotHit = std::numeric_limits<double>::infinity();

/// @brief The result of one integration. Fixed size: filling it never allocates.
struct ShaftIntegral {
    double lengthMm = 0;        ///< |tip - entry| [mm]
    double dampingIntegral = 0; ///< ∫β ds [N·s/mm]: the damping force at speed v [mm/s] is v times this
    std::array<double, kMaxLabels> labelLengthMm{}; ///< shaft length in each label [mm] (air outside the volume)
    std::array<double, kMaxLabels>
        firstHitMm{}; ///< distance from the entry to each label's first voxel [mm], or kNotHit
    bool labelsValid =
        false; ///< labels were tracked (the integrator had a label grid and was asked to); else the arrays mean nothing

    /// @brief Zero the result. The label arrays (1 KiB) are cleared only when
    /// @p withLabels: an integrator that tracks no labels leaves labelsValid
    /// false, and then the arrays mean nothing (at servo rate the fill was a
    /// tenth of a short shaft's integration).
    void reset(bool withLabels = true) noexcept
    {
        lengthMm = 0;
        dampingIntegral = 0;
        if (withLabels) {
            labelLengthMm.fill(0.0);
            firstHitMm.fill(kNotHit);
        }
        labelsValid = false;
    }
    /// @brief Damping force magnitude for insertion speed @p speedMmPerS [N].
    double dampingForceN(double speedMmPerS) const noexcept { return dampingIntegral * speedMmPerS; }
};

/// @brief One way of integrating along the shaft.
/// @warning Not thread-safe: each thread uses its own (clone()).
class ShaftIntegrator {
public:
    virtual ~ShaftIntegrator() = default;
    /// @brief Integrate along @p s into @p out. Never throws or allocates; a
    /// non-finite or degenerate input gives zero integrals.
    virtual void integrate(const Segment& s, ShaftIntegral& out) noexcept = 0;
    /// @brief Integrate along a bent shaft, the polyline @p points[0] → … → the
    /// last (physics.md §9.5): the sum over its segments, lengthMm its length and
    /// first hits measured along it from its first point. Never throws or
    /// allocates; a non-finite point or fewer than two points give zero integrals.
    virtual void integratePolyline(std::span<const Vec3d> points, ShaftIntegral& out) noexcept = 0;
    /// @brief An independent copy for another thread.
    virtual std::unique_ptr<ShaftIntegrator> clone() const = 0;
    /// @brief Short name for tables, e.g. "exact-voxel", "march-trilinear h=0.125mm".
    virtual std::string name() const = 0;
};

/// @brief The strategies behind ShaftIntegrator.
enum class Strategy {
    ExactVoxel,     ///< Amanatides–Woo over voxel cells, each weighted by its exact chord [mm]
    ExactTrilinear, ///< cell by cell, the cubic along the chord integrated in closed form
    MarchNearest,   ///< fixed step, nearest-voxel samples, trapezoid rule
    MarchTrilinear, ///< fixed step, trilinear samples, trapezoid rule
    Profile,        ///< cumulative integral along a locked line, O(1) per query (TrajectoryProfile)
};

/// @brief Strategy and its knobs.
struct IntegratorOptions {
    Strategy strategy = Strategy::ExactVoxel;
    double stepMm = 0.125;             ///< ray march step [mm]
    bool trackLabels = true;           ///< fill label lengths and first hits
    double profileToleranceMm = 0.05;  ///< profile: rebuild when the shaft is farther than this from the line
    double profileMaxLengthMm = 300.0; ///< profile: how far along the line the profile reaches
};

/// @brief Make an integrator over @p field (which must outlive it).
/// @throw ValueError if the field lacks what the options need
std::unique_ptr<ShaftIntegrator> makeIntegrator(const MaterialField& field, const IntegratorOptions& options);

} // namespace voxhap::haptic
