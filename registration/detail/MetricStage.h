// SPDX-License-Identifier: Apache-2.0
/// @file MetricStage.h
/// @brief One optimisation stage of ITK's v4 registration framework on one
/// pair of level images: Mattes mutual information over body samples of the
/// fixed image, a regular-step gradient descent over an Euler 3D (rigid) or an
/// affine transform. ITK stays inside this folder's .cpp files.
#pragma once

#include "registration/AffineMap.h"
#include "registration/LevelImage.h"

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace voxhap::registration::detail {

/// @brief The transform a stage optimises.
enum class StageKind {
    Rigid,  ///< itk::Euler3DTransform: three angles and a translation
    Affine, ///< itk::AffineTransform: twelve parameters
};

struct StageSettings {
    StageKind kind = StageKind::Rigid;
    int iterations = 200;        ///< the optimiser's limit
    int samples = 4000;          ///< fixed-image body samples, drawn once per stage
    int bins = 32;               ///< histogram bins of the mutual information
    double stepMm = 2.0;         ///< the optimiser's first step, as a shift of the body [mm]
    double minimumStepMm = 0.01; ///< it stops once its step falls below this [mm]
    /// The step's factor each time the gradient turns back [chosen: ITK's 0.5
    /// stopped the finest level of the porcine pair after 10–20 iterations,
    /// wherever the sampled metric's noise first turned it; 0.8 lets it average
    /// over three times as many, and its answer moved half a millimetre closer
    /// to elastix's on every seed of elastix tried].
    double relaxation = 0.8;
    std::uint32_t seed = 20261127; ///< the samples' generator: the same run gives the same answer
    /// Samples anywhere within their fixed voxel (true), or at its centre.
    /// Coarse levels need the jitter: on a lattice of samples a few
    /// millimetres apart the metric has ridges where the moving voxels line up
    /// with it, and without it the lumbar phantom's orientation search followed
    /// one into a wrong turn. At the finest level the centres read the CT's own
    /// values, where a jittered sample reads it through linear interpolation
    /// (Registration.cpp, kFinestAtCentres, says what that gained).
    bool jittered = true;
};

struct StageResult {
    AffineMap map;          ///< mr_from_ct at the end (the best value the optimiser saw)
    double startMetric = 0; ///< Mattes MI (negative: lower is better) at the start
    double finalMetric = 0; ///< at the end
    int iterations = 0;
    bool hitIterationLimit = false;
    std::string stopReason;      ///< the optimiser's own words
    std::vector<double> history; ///< the metric after each iteration
};

/// @brief A fixed (CT) and a moving (MR) level image as ITK images with their
/// body masks; stages run on it from any start.
class MetricPair {
public:
    /// @param marginMm the bodies grown by this much into the air around them
    ///        (within a voxel), so that the skin's edge is sampled
    /// @param workUnits each metric evaluation's samples split in this many
    ///        parts, run in parallel (the answer depends on the count, not on
    ///        the threads' timing)
    /// @param movingCropVoxels the moving image handed to ITK is the box of its
    ///        mask grown by this many voxels (kMovingCropVoxels reads every voxel
    ///        the whole image would give); negative: the whole image
    MetricPair(const LevelImage& fixed, const LevelImage& moving, double marginMm, int workUnits = 1,
        int movingCropVoxels = kMovingCropVoxels);
    /// Half a voxel to the sample, one to its interpolation's far voxel, one to
    /// a central difference's: MetricStage.cpp, toItkCropped.
    static constexpr int kMovingCropVoxels = 3;
    ~MetricPair();
    MetricPair(const MetricPair&) = delete;
    MetricPair& operator=(const MetricPair&) = delete;

    /// @brief Optimise from @p start, rotations about @p centre (world, mm).
    /// @throw ValueError when too few samples land inside the moving image
    StageResult run(const AffineMap& start, const Vec3d& centre, const StageSettings& settings) const;
    /// @brief The metric at @p map without optimising (samples as in @p settings).
    double metricAt(const AffineMap& map, const Vec3d& centre, const StageSettings& settings) const;
    /// @brief The metric and its derivative by the transform's parameters at
    /// @p map (the optimiser's first step reads these).
    std::pair<double, std::vector<double>> metricAndDerivativeAt(
        const AffineMap& map, const Vec3d& centre, const StageSettings& settings) const;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace voxhap::registration::detail
