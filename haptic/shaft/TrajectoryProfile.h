// SPDX-License-Identifier: Apache-2.0
/// @file TrajectoryProfile.h
/// @brief O(1) shaft integrals once the needle is locked to a line (architecture.md
/// "Shaft integration"; the trajectory lock of [S19], physics.md §2.1).
///
/// After skin puncture the needle moves along one line, so the cumulative
/// integral C(s) = ∫₀ˢ β along that line is built once (one exact voxel
/// traversal) and every query is a table lookup: C is piecewise linear between
/// voxel faces, runs of equal voxels are merged, and a uniform bucket index
/// finds the run holding s in a bounded number of steps.
///
/// Guarantees, for the piecewise-constant field (the exact-voxel reading):
/// - on the line: the exact integral, up to round-off (≤ 1e-12 relative);
/// - off the line: for a shaft whose entry and tip lie within the tolerance δ
///   of the line, |exact − profile| ≤ errorBound(segment), where the bound is
///   (ℓ'/ℓ)·Σ_v span_v·M_v(δ): over the voxels v the line crosses, span_v is
///   the largest |Δβ| between v and its 26 neighbours, and M_v(δ) the length of
///   the line inside v that lies within δ of a face of v (measured across the
///   line, where a sideways displacement of at most δ can carry the shaft).
///   The shaft and the line sample different voxels only there. Inside uniform
///   tissue span_v = 0 and the bound vanishes; it grows only near interfaces.
/// A shaft farther than δ from the line triggers a rebuild along the new line;
/// a shaft longer than the profile's reach, or bent (a polyline), is integrated
/// directly (exact voxel).
#pragma once

#include "haptic/shaft/ShaftIntegration.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace voxhap::haptic {

/// @brief The trajectory-profile strategy. See the file comment for its error bound.
/// @warning Not thread-safe; clone() per thread. Builds and queries never allocate
/// after construction (buffers are reserved for the maximum length).
class TrajectoryProfile final : public ShaftIntegrator {
public:
    /// @param toleranceMm  farthest distance of entry and tip from the line before a rebuild [mm];
    ///                     must be below half the smallest voxel size
    /// @param maxLengthMm  how far along the line the profile reaches [mm]
    TrajectoryProfile(const MaterialField& field, double toleranceMm, double maxLengthMm, bool trackLabels);
    ~TrajectoryProfile() override;
    TrajectoryProfile(const TrajectoryProfile& other);
    TrajectoryProfile& operator=(const TrajectoryProfile&) = delete;

    /// @brief Integrate; rebuilds along entry -> tip first if the shaft is off the line.
    void integrate(const Segment& s, ShaftIntegral& out) noexcept override;
    /// @brief A bent shaft leaves the line: integrated directly (exact voxel) along
    /// the polyline, the profile kept for the straight shaft (physics.md §9.5).
    void integratePolyline(std::span<const Vec3d> points, ShaftIntegral& out) noexcept override;
    std::unique_ptr<ShaftIntegrator> clone() const override;
    std::string name() const override;

    /// @brief Lock to the line through @p origin along @p direction (O(length/voxel)).
    /// @return false (and no line) for a zero or non-finite direction.
    bool lock(const Vec3d& origin, const Vec3d& direction) noexcept;
    /// @brief True if entry and tip are within the tolerance of the locked line.
    bool covers(const Segment& s) const noexcept;
    /// @brief Bound on |exact-voxel ∫β − profile ∫β| for @p s [N·s/mm]; valid when covers(s).
    double errorBound(const Segment& s) const noexcept;

    std::uint64_t rebuilds() const { return mRebuilds; }
    std::size_t runs() const;
    double toleranceMm() const { return mTolerance; }

private:
    /// integrate()'s rare paths: a shaft beyond the profile's reach (integrated
    /// directly; returns false) or off the line (relocked; false if that fails).
    [[gnu::noinline]] bool integrateOffLine(const Segment& s, double length, ShaftIntegral& out) noexcept;
    /// The label lengths and first hits between arc lengths se and st (runs ke, kt).
    [[gnu::noinline]] void fillLabels(
        double se, double st, std::size_t ke, std::size_t kt, double scale, ShaftIntegral& out) const noexcept;

    struct Impl;
    std::unique_ptr<Impl> mImpl;
    double mTolerance;
    double mMaxLength;
    std::uint64_t mRebuilds = 0;
};

} // namespace voxhap::haptic
