// SPDX-License-Identifier: Apache-2.0
/// @file Layers.h
/// @brief Hand-made layer stacks for force-model tests: the expected forces come
/// from the numbers set here, not from the tissue table.
#pragma once

#include "haptic/Layer.h"

#include <vector>

namespace voxhap::test {

/// Fat from 0 to @p boneMm with cutting force @p fatCuttingN, then 10 mm of rigid
/// cortical bone (contact, physics.md §1.3).
inline std::vector<haptic::Layer> fatOverBone(double boneMm, double fatCuttingN = 0.0)
{
    haptic::Layer fat;
    fat.name = "fat";
    fat.startMm = 0.0;
    fat.endMm = boneMm;
    fat.cuttingForceN = fatCuttingN;
    haptic::Layer bone;
    bone.name = "cortical_bone";
    bone.role = haptic::LayerRole::Bone;
    bone.rigid = true;
    bone.startMm = boneMm;
    bone.endMm = boneMm + 10.0;
    return {fat, bone};
}

} // namespace voxhap::test
