// SPDX-License-Identifier: Apache-2.0
/// @file Registration.h
/// @brief Rigid (and optionally affine) registration of an MR onto a CT of the
/// same patient, on ITK's v4 framework: Mattes mutual information over the
/// bodies, multi-resolution, started from the header geometry or from the best
/// of the 24 axis-aligned orientations (docs/reference.md "CT and MR fusion").
///
/// The result maps CT points to MR points (`mr_from_ct`, AffineMap.h). Stages
/// compose into one affine map; a deformable stage would follow them as a
/// displacement applied after the affine map, which is why the stages are
/// listed rather than folded into the map alone.
#pragma once

#include "core/Progress.h"
#include "registration/AffineMap.h"
#include "volume/Volume.h"

#include <cstdint>
#include <string>
#include <vector>

namespace voxhap::registration {

/// @brief How the optimiser's start is found.
enum class StartRule {
    Search,   ///< the best of 24 axis-aligned turns about the body's centre, by the metric
    Geometry, ///< the header geometry as it is (the same frame of reference)
};

struct RegistrationOptions {
    StartRule start = StartRule::Search;
    bool affine = false;   ///< an affine stage after the rigid one (--affine)
    double finestMm = 1.2; ///< voxel size of the finest level [mm] [chosen: sub-millimetre agreement needs no finer]
    int levels = 3;        ///< each coarser level doubles the voxel size
    int iterations = 250;  ///< the optimiser's limit per level
    /// Body samples per level, coarsest first (the last repeats) [chosen: the
    /// finest level's metric is the answer's noise; 20000 samples cost about
    /// 4 ms an iteration on one core].
    std::vector<int> samples{2000, 3000, 20000};
    int bins = 32; ///< histogram bins of the mutual information
    std::uint32_t seed = 20261127;
    /// Refuse a result that fails the body-surface check (off: report it in the
    /// warnings only, for studying a refusal).
    bool refuseFailedSurfaceCheck = true;
    Progress progress;
};

/// @brief One start the orientation search tried.
struct OrientationCandidate {
    Mat3d rotation = Mat3d::Identity(); ///< applied to the CT about its body's centre
    std::string name;                   ///< "identity", "180° about A–P", ...
    double metric = 0;                  ///< after the short coarse run (lower is better)
    bool refined = false;               ///< among the few carried to the next level
};

/// @brief One stage of the chain, for the report.
struct StageReport {
    std::string kind; ///< "rigid" or "affine"
    int level = 0;    ///< 0: the coarsest
    double voxelMm = 0;
    int iterations = 0;
    double startMetric = 0, finalMetric = 0;
    std::string stopReason;
};

struct RegistrationResult {
    AffineMap mrFromCt;                           ///< the answer (rigid, or rigid then affine)
    AffineMap start;                              ///< where the optimiser began
    std::string startedFrom;                      ///< how the start was chosen, in words
    std::vector<OrientationCandidate> candidates; ///< the search's, empty without one
    std::vector<StageReport> stages;
    double metricGeometry = 0; ///< Mattes MI at the header geometry, finest level
    double metricStart = 0;    ///< at the optimiser's start, finest level
    double metricFinal = 0;    ///< at the answer, finest level
    int iterations = 0;        ///< all stages together
    std::string stopReason;    ///< of the last stage
    bool converged = true;     ///< false: the finest stage hit its limit while the metric still moved
    std::vector<std::string> warnings;
    double overlapStart = 0;      ///< fraction of the MR body inside the CT's field of view at the start
    double overlapFinal = 0;      ///< and at the answer
    double surfaceDistanceMm = 0; ///< mean distance of the CT's skin to the registered MR body surface
    double surfaceLimitMm = 0;    ///< the refusal threshold: two MR voxel diagonals
    std::int64_t surfacePoints = 0;
    double searchSeconds = 0; ///< of which the orientation search
    double seconds = 0;       ///< the whole registration, from the loaded volumes
};

/// @brief The channel of @p mr a registration reads: t1, else intensity.
volume::Channel movingChannel(const volume::Volume& mr);

/// @brief Register @p mr (moving) onto @p ct (fixed).
/// @throw ValueError "too little overlap" when less than 20 % of the MR body lies
///        inside the CT at the start, "failed the body-surface check" when the
///        registered surfaces lie more than two MR voxel diagonals apart, or when
///        a volume lacks its channel or body
RegistrationResult registerMrToCt(
    const volume::Volume& ct, const volume::Volume& mr, const RegistrationOptions& options = {});

/// @brief The 24 rotations that map the coordinate axes onto themselves, the identity first.
std::vector<Mat3d> axisTurns();
/// @brief A rotation in words: "identity", "180° about A–P", "90° about S–I", "120° about (1, 1, 1)".
std::string describeRotation(const Mat3d& r);

/// @brief Minimum overlap at the start (fraction of the MR body in the CT).
inline constexpr double kMinimumOverlap = 0.20;

} // namespace voxhap::registration
