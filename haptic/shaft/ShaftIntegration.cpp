// SPDX-License-Identifier: Apache-2.0
/// @file ShaftIntegration.cpp
/// @brief The strategy factory.

#include "haptic/shaft/ShaftIntegration.h"

#include "haptic/shaft/ExactTraversal.h"
#include "haptic/shaft/RayMarch.h"
#include "haptic/shaft/TrajectoryProfile.h"

namespace voxhap::haptic {

std::unique_ptr<ShaftIntegrator> makeIntegrator(const MaterialField& field, const IntegratorOptions& o)
{
    switch (o.strategy) {
    case Strategy::ExactVoxel:
        return makeExactVoxel(field, o.trackLabels);
    case Strategy::ExactTrilinear:
        return makeExactTrilinear(field, o.trackLabels);
    case Strategy::MarchNearest:
        return makeRayMarch(field, o.stepMm, false, o.trackLabels);
    case Strategy::MarchTrilinear:
        return makeRayMarch(field, o.stepMm, true, o.trackLabels);
    case Strategy::Profile:
        return std::make_unique<TrajectoryProfile>(field, o.profileToleranceMm, o.profileMaxLengthMm, o.trackLabels);
    }
    return makeExactVoxel(field, o.trackLabels);
}

} // namespace voxhap::haptic
