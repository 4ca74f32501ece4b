// SPDX-License-Identifier: Apache-2.0
/// @file PlanningFixtures.h
/// @brief The torso phantom at 1 mm with its critical structures' distance fields,
/// built once per test binary, and brute-force references that do not use the code
/// under test.
#pragma once

#include "common/BuiltinTable.h"
#include "haptic/scene/Scene.h"
#include "phantoms/Phantoms.h"
#include "planning/Planner.h"
#include "segmentation/Segmentation.h"
#include "volume/Grids.h"

#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace voxhap::test {

/// Phantom voxel size [mm]: coarse enough for a fast fixture, fine enough that the
/// 1.5 mm cortical shell and the 2 mm skin stay closed.
inline constexpr double kTorsoSpacingMm = 1.0;

struct TorsoFixture {
    volume::PhantomModel model;
    std::shared_ptr<volume::Volume> volume;
    haptic::Scene scene;
    std::unique_ptr<planning::Planner> planner;
    Vec3d lesion{0, 0, 0}, entry{0, 0, 0};
};

/// The phantom's own labels (exact geometry) with the distance fields segment()
/// adds; the kyung scene (spine biopsy on the torso, physics.md §1).
inline const TorsoFixture& torso()
{
    static const TorsoFixture f = [] {
        TorsoFixture t;
        t.model = volume::torsoModel({}, table());
        volume::GridSpec g;
        g.spacing = Vec3d::Constant(kTorsoSpacingMm);
        t.volume = std::make_shared<volume::Volume>(volume::makePhantom(t.model, g, table()));
        segmentation::SegmentOptions so;
        so.automatic = false; // keep the phantom's labels: planning is tested, not segmentation
        segmentation::segment(*t.volume, table(), so);
        t.scene = haptic::loadScene("kyung");
        t.planner = std::make_unique<planning::Planner>(t.volume, table(), t.scene);
        t.lesion = *volume::phantomLandmark(*t.volume, "lesion");
        t.entry = *volume::phantomLandmark(*t.volume, "entry");
        return t;
    }();
    return f;
}

/// Distance from the segment a–b to the nearest voxel centre labelled @p tissue, by
/// brute force over the label grid's active voxels [mm].
inline double bruteForceClearance(const volume::Volume& v, const std::string& tissue, const Vec3d& a, const Vec3d& b)
{
    const int id = table().at(tissue).id;
    const auto labels = volume::labelGrid(v);
    const Vec3d ab = b - a;
    const double len2 = ab.squaredNorm();
    double best = std::numeric_limits<double>::infinity();
    for (auto it = labels->cbeginValueOn(); it; ++it) {
        if (*it != id) continue;
        const Vec3d p = volume::fromVdb(labels->indexToWorld(it.getCoord()));
        const double s = std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
        best = std::min(best, (a + s * ab - p).norm());
    }
    return best;
}

} // namespace voxhap::test
