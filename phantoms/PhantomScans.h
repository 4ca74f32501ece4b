// SPDX-License-Identifier: Apache-2.0
/// @file PhantomScans.h
/// @brief A phantom scanned twice, as a patient is: a CT (hu only) on the
/// phantom's lattice, and an MR T1 map of the same body moved by a known rigid
/// map, on a coarser lattice of its own, with Rician noise. The pair tests CT–MR
/// registration against a transform known exactly (physics.md §7 "The phantoms",
/// docs/reference.md "CT and MR fusion").
#pragma once

#include "phantoms/Phantoms.h"

#include <cstdint>
#include <filesystem>

namespace voxhap::volume {

/// @brief How the MR scan of a phantom is taken.
struct PhantomMrScan {
    /// The body's pose in the MR: a CT point x is the MR point
    /// rotation·(x − centre) + centre + translation (centre: the model's bounds'
    /// centre). Identity: the MR sees the body where the CT does.
    Mat3d rotation = Mat3d::Identity();
    Vec3d translationMm = Vec3d::Zero();
    Vec3d spacing{1.0, 1.0, 4.0};  ///< MR voxel size [mm], axis-aligned in the MR's frame
    double noiseOfMuscleT1 = 0.05; ///< Rician σ as a fraction of muscle's T1
    std::uint64_t seed = 1;        ///< the noise generator's seed
    FieldStrength field = FieldStrength::T1_5;
    int supersample = 2; ///< samples per axis averaged in a voxel (partial volume)
};

/// @brief The true map of a scan pair: CT point → MR point, y = linear·x + offset.
struct PhantomScanTruth {
    Mat3d linear = Mat3d::Identity();
    Vec3d offset = Vec3d::Zero();
    Vec3d apply(const Vec3d& x) const { return linear * x + offset; }
};

/// @brief The CT of a phantom: its hu grid alone, modality "CT".
Volume phantomCtScan(const PhantomModel& model, const GridSpec& grid, const TissueTable& table);

/// @brief The MR of a phantom: a t1 grid (T1 [ms] at @p scan.field, averaged over
/// each voxel, then Rician noise) over the whole moved body and a margin of air,
/// every voxel active as a scanner's image is; modality "MR", weighting "T1 map".
/// @param truth receives the true CT → MR map
Volume phantomMrScan(
    const PhantomModel& model, const TissueTable& table, const PhantomMrScan& scan, PhantomScanTruth* truth = nullptr);

/// @brief The BIDS sidecar of a phantom MR: an MR T1 map at @p field, as JSON text.
std::string phantomMrSidecar(FieldStrength field);

/// @brief Write @p mr as a scanner's export: a plain .nrrd (no voxhap keys) and a
/// BIDS sidecar beside it declaring an MR T1 map at its field strength.
/// @throw IoError naming the file
void writePhantomMrScan(const Volume& mr, FieldStrength field, const std::filesystem::path& nrrd);

} // namespace voxhap::volume
