// SPDX-License-Identifier: Apache-2.0
/// @file Suite.h
/// @brief Regression suites (`voxhap regress`): a JSON file of cases,
/// each a volume (a phantom spec or a volume file), a scene, a tissue table,
/// an insertion, a shaft-integration strategy and the tolerances its force
/// profile is compared with. The schema is documented in data/regress/README.md;
/// every refusal names the file, the case and the field in one line.
#pragma once

#include "core/Math.h"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::regress {

/// @brief What a case compares, and how closely.
struct Tolerance {
    // The runs are deterministic bit for bit: the defaults only
    // absorb a different compiler's rounding, and stay far below the smallest
    // effect of a few-percent edit (3 % of the skin's viscous friction moves the
    // Sénac profiles by 2.5e-7 N at 2 mm/s).
    double absN = 1e-9;         ///< profile: |ΔF| allowed at each depth [N] ...
    double rel = 1e-9;          ///< ... plus this fraction of the reference |F|
    double peakN = 1e-9;        ///< peak model and rendered force [N]
    double eventDepthMm = 0.01; ///< depth of each event [mm]
    bool eventCounts = true;    ///< the count of each kind of event, exactly
};

/// @brief The volume of a case: a phantom built from its parameters, or a file.
struct VolumeSpec {
    std::string kind;               ///< "slab", "sphere", "lumbar", "torso", or "file"; empty: the scene's
    std::string file;               ///< kind "file": a .vdb or other volume (relative to the suite)
    Vec3d spacingMm{0.5, 0.5, 0.5}; ///< phantom voxel size [mm]
    Vec3d rotationDeg{0, 0, 0};     ///< grid rotation, Euler angles about x, then y, then z [deg]
    double tiltDeg = 0;             ///< slab: layer normal tilted from +y about x [deg]
    std::vector<std::pair<std::string, double>> layers; ///< slab: (tissue, thickness [mm]); empty: the default stack
    std::string preset = "average";                     ///< lumbar preset
    std::optional<double> bmi;                          ///< lumbar BMI
    std::string slabTissue = "fat", sphereTissue = "muscle"; ///< sphere phantom
    double radiusMm = 10, slabThicknessMm = 40;              ///< sphere phantom [mm]
    double lesionRadiusMm = 8;                               ///< torso [mm]
    /// slab: fuse a second scan of the phantom as the MR (docs/physics.md §7
    /// R1, "Fused"): the phantom rasterised again on a grid turned by turnDeg
    /// about the layers' normal (y), its frame moved by shiftMm, and its t1
    /// resampled onto the CT's grid through that exact map (no registration),
    /// or through it with mapErrorMm added: a registration error whose effect
    /// on the force a case can show.
    struct FusedMr {
        double turnDeg = 0;
        Vec3d shiftMm = Vec3d::Zero();
        Vec3d mapErrorMm = Vec3d::Zero();
    };
    std::optional<FusedMr> fusedMr;
};

/// @brief The shaft-integration strategies a case may name ("sampler strategies").
/// "servo" is what the servo loop runs (exact voxel off the path, the locked
/// profile on it: haptic::SceneInstance::makeModel).
inline const std::vector<std::string> kStrategies = {
    "servo", "exact-voxel", "exact-trilinear", "march-trilinear", "march-nearest"};

/// @brief A deflection measured in the literature that a bending case's run is
/// held to (physics.md §9.2): the bent tip's distance from the straight line at
/// the last tick, within the stated tolerance.
struct Measured {
    double tipDeviationMm = 0; ///< the measurement [mm]
    double toleranceMm = 0;    ///< allowed |model − measurement| [mm], > 0
    std::string source;        ///< who measured it, with what, in what
};

/// @brief A palpation sweep across the back (a case kind of its own): the
/// fingertip comes down onto the skin at @ref from, presses @ref pressMm in along
/// the scene's path direction, slides to @ref to at that depth and lifts, at a
/// constant speed. The profile is the push out of the skin against the distance
/// travelled; the scene must turn palpation on.
struct PalpationSweep {
    Vec3d from{0, 0, 0}, to{0, 0, 0}; ///< points on the skin [mm, LPS]
    double pressMm = 2.0;             ///< indentation below them, along the path direction [mm]
    double speedMmPerS = 10.0;        ///< along the whole motion [mm/s]
    double aboveMm = 5.0;             ///< the motion starts and ends this far outside the skin [mm]
};

/// @brief One regression case.
struct Case {
    std::string name;                          ///< unique; [a-z0-9._-]; also the baseline's file name
    std::string scene;                         ///< built-in scene name or a scene file (relative to the suite)
    std::string tissues;                       ///< tissue table file (relative to the suite); empty: the built-in table
    VolumeSpec volume;                         ///< kind empty: the scene's own phantom
    std::optional<Vec3d> entry, target;        ///< path [mm, LPS]; else landmarks, else the phantom's reference path
    std::string entryLandmark, targetLandmark; ///< override the scene's landmarks
    std::optional<double> speedMmPerS, depthMm; ///< else the scene's
    std::string script;                         ///< motion script CSV (relative to the suite); empty: constant speed
    std::optional<PalpationSweep> sweep;        ///< a palpation sweep instead of an insertion
    std::string strategy = "servo";
    double sampleMm = 0.2; ///< spacing of the stored profile samples along the depth [mm]
    Tolerance tolerance;
    std::optional<Measured> measured; ///< a literature deflection (bending scenes only)
};

/// @brief A parsed suite.
struct Suite {
    std::string origin;                 ///< the file, or "builtin"
    std::filesystem::path dir;          ///< relative paths in the suite are relative to this
    std::filesystem::path baselinesDir; ///< where the baselines are
    /// The built-in suite read from the copy compiled into the binary (its source
    /// folder is not on this machine): its baselines are compiled in too, and
    /// `--update` has nowhere to write them.
    bool compiledIn = false;
    std::string description;
    std::vector<Case> cases;
};

/// @brief Parse suite JSON; relative paths resolve against @p dir.
/// @throw ValueError "origin: cases[i] (name).field: why"
Suite parseSuite(const std::string& text, const std::string& origin, const std::filesystem::path& dir);
/// @brief Read and parse a suite file. @throw IoError, ValueError
Suite loadSuite(const std::filesystem::path& file);
/// @brief The built-in suite: data/regress/suite.json of the source tree, with its
/// baselines beside it, where that folder exists (a build tree: `--update` writes
/// there); else the copy compiled into the binary (an installed voxhap).
Suite builtinSuite();
/// @brief The folder of the built-in suite and its baselines in the source tree.
std::filesystem::path builtinSuiteDir();
/// @brief The text of data/regress/@p file as compiled into the binary; nullptr if absent.
const std::string* builtinRegressFile(const std::string& file);

/// @brief True when @p name matches @p pattern: a shell glob (*, ?, [..]) or, without
/// glob characters, a substring; several patterns separated by commas.
bool matchesPattern(const std::string& name, const std::string& pattern);

} // namespace voxhap::regress
