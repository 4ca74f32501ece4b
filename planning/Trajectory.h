// SPDX-License-Identifier: Apache-2.0
/// @file Trajectory.h
/// @brief What one straight needle path meets: the tissue
/// segments in order, the clearance to each critical structure, the bone it
/// crosses, the force the scene's model predicts along it, warnings and a
/// risk score (RiskScore.h). World space is LPS in mm.
#pragma once

#include "core/Math.h"

#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::planning {

inline constexpr double kNoDepth = std::numeric_limits<double>::infinity();

/// @brief One run of one tissue along the path, depths from the entry [mm].
struct TissueSegment {
    std::string tissue;
    int label = 0;
    double startMm = 0, endMm = 0;
    bool critical = false, rigid = false;
    double lengthMm() const { return endMm - startMm; }
};

/// @brief Closest approach of the path (entry to target, the needle's axis) to
/// one critical structure's surface, read from its signed distance field.
struct Clearance {
    std::string tissue;
    double minMm = 0;        ///< negative: the path enters the structure
    double atDepthMm = 0;    ///< where along the path [mm from the entry]
    bool beyondBand = false; ///< the field stores distances only within its band: the clearance is at least minMm
};

/// @brief Predicted axial resistance at one tip depth [N].
struct ForceSample {
    double depthMm = 0, forceN = 0;
};

/// @brief A machine-readable code and a human sentence.
struct Warning {
    std::string code; ///< "critical_breach", "clearance_below_minimum", "force_above_device_limit",
                      ///< "needle_too_short", "bone_before_target"
    std::string message;
};

/// @brief The terms of the risk score (RiskScore.h gives the formula).
struct RiskTerms {
    double breach = 0, tooShort = 0, boneObstacles = 0, overForce = 0; ///< hard terms (flags and counts)
    double proximity = 0, length = 0, force = 0;                       ///< soft terms, each in [0, 1] per unit
    double total = 0;
};

/// @brief One way of inserting a bending needle along a straight plan (physics.md §9.6).
struct BevelChoice {
    double orientationDeg = 0;     ///< the bevel's orientation at the entry (the scene's, or turned 180°)
    double turnDepthMm = kNoDepth; ///< one half turn at this depth [mm], or none
    double tipDeviationMm = 0;     ///< the bent tip's distance from the planned line at the target's depth [mm]
    double tipToTargetMm = 0;      ///< the bent tip's distance from the target [mm]
};

/// @brief The predicted deflection of a path: each orientation and turn tried, the
/// one ending nearest the target, and that one's bent needle.
struct DeflectionPrediction {
    std::vector<BevelChoice> tried; ///< the scene's orientation, its reverse, then each turn depth
    BevelChoice best;
    std::vector<Vec3d> bentShaft; ///< the best choice's needle at the end, hub to tip [mm, LPS]
    std::vector<Vec3d> bentTrack; ///< the track its tip cut, from the entry [mm, LPS]
};

struct TrajectoryReport {
    Vec3d entry{0, 0, 0}, target{0, 0, 0};
    double lengthMm = 0;
    std::string targetTissue;            ///< the tissue at the target point
    std::vector<TissueSegment> segments; ///< entry to target, in order (air inside the body kept)
    std::vector<Clearance> clearances;   ///< one per critical structure with a distance field
    double minClearanceMm = kNoDepth;    ///< smallest of clearances
    std::string nearestStructure;
    int boneEntries = 0;            ///< separate bone runs entered before the target
    int boneObstacles = 0;          ///< ... of them not the bone holding the target (see Planner.cpp)
    double firstBoneMm = kNoDepth;  ///< depth of the first bone [mm]
    double speedMmPerS = 0;         ///< of the force prediction
    std::vector<ForceSample> force; ///< predicted profile, entry to first rigid contact or target
    double peakForceN = 0, peakDepthMm = 0;
    double contactMm = kNoDepth; ///< the profile stops at rigid (bone) contact here (physics.md §1.3)
    std::vector<Warning> warnings;
    RiskTerms risk;
    /// With a bending needle (scene terms.bending): where its tip is predicted to end
    /// (Deflection.h); filled for the ranked paths only.
    std::optional<DeflectionPrediction> deflection;
    bool hasWarning(const std::string& code) const;
};

} // namespace voxhap::planning
