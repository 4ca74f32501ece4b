// SPDX-License-Identifier: Apache-2.0
/// @file Planner.h
/// @brief Everything a path analysis reads, built once per volume and scene:
/// the material field of the scene's force model, the tissue table and the
/// critical structures' distance fields. analyze() is const and thread-safe,
/// so the candidate search (Search.h) calls it from many TBB tasks.
#pragma once

#include "haptic/papers/LayerTables.h"
#include "haptic/scene/Scene.h"
#include "haptic/shaft/LabelTrace.h"
#include "planning/Trajectory.h"
#include "volume/TissueTable.h"
#include "volume/Volume.h"

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::planning {

struct PlanOptions {
    double speedMmPerS = 0;      ///< insertion speed of the force prediction; 0: the scene's
    double profileStepMm = 1.0;  ///< depth step of the predicted force profile [mm]
    double minClearanceMm = 5.0; ///< closer than this to a critical structure warns [chosen: a needle's
                                 ///< lateral deflection over 10 cm is a few mm]
    double marginMm = 20.0;      ///< structures nearer than this raise the risk (RiskScore.h) [chosen]
    /// Clearance is found to within this [mm]; 0: half the finest voxel (the field's own accuracy, DistanceField.h).
    double clearanceToleranceMm = 0;
};

/// @brief The memory a Planner adds to @p v [bytes]: the material field's grids
/// (damping and bone stiffness, at most one value per labelled voxel each), estimated
/// from the label grid's active voxels before they are built.
std::uint64_t plannerWorkingBytes(const volume::Volume& v);

/// @brief Refuse, in one line naming both figures, when @p v's grids plus
/// plannerWorkingBytes() exceed @p capBytes (0: no cap). @throw ValueError
void checkMemoryCap(const volume::Volume& v, std::uint64_t capBytes);

class Planner {
public:
    /// @param volume labelled (segmented or phantom) volume; its "sdf.<tissue>" derived
    ///        grids give the clearances (segmentation::segment makes them)
    /// @throw ValueError if the volume has no label grid or an option is out of range
    Planner(std::shared_ptr<const volume::Volume> volume, const volume::TissueTable& table, const haptic::Scene& scene,
        const PlanOptions& options = {});
    ~Planner();

    /// @brief Analyse the straight path entry → target. @throw ValueError on coincident or non-finite points
    TrajectoryReport analyze(const Vec3d& entry, const Vec3d& target) const;

    /// @brief The same, from the label runs already traced outward from the target along
    /// -direction up to the entry (Search.h traces them to find the entry).
    TrajectoryReport analyzeTraced(const Vec3d& entry, const Vec3d& target,
        const std::vector<haptic::LabelRun>& runsFromTarget,
        const std::vector<haptic::DampingPiece>& dampingFromTarget) const;

    /// @brief The label runs from @p origin along @p direction over @p lengthMm (leading and
    /// trailing air dropped), and β along it when @p damping is given and the scene damps.
    std::vector<haptic::LabelRun> trace(const Vec3d& origin, const Vec3d& direction, double lengthMm,
        std::vector<haptic::DampingPiece>* damping = nullptr) const;

    const volume::Volume& volume() const { return *mVolume; }
    const volume::TissueTable& table() const { return mTable; }
    const haptic::Scene& scene() const { return mScene; }
    const PlanOptions& options() const { return mOptions; }
    double speedMmPerS() const { return mSpeed; }
    /// @brief Names of the critical structures whose distance fields are read.
    std::vector<std::string> criticalStructures() const;
    double distanceBandMm() const { return mBandMm; }
    int skinLabel() const { return mSkin; }
    int labelAt(const Vec3d& world) const;
    /// @brief The scene's material field over the volume (the bending prediction's foundation).
    const haptic::MaterialField& field() const;

private:
    struct Impl;
    TrajectoryReport finish(
        TrajectoryReport r, std::vector<haptic::LabelRun> runs, std::vector<haptic::DampingPiece> damping) const;

    std::shared_ptr<const volume::Volume> mVolume;
    const volume::TissueTable& mTable;
    haptic::Scene mScene;
    PlanOptions mOptions;
    double mSpeed = 0, mBandMm = 0;
    int mSkin = -1;
    std::unique_ptr<Impl> mImpl;
};

} // namespace voxhap::planning
