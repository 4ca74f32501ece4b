// SPDX-License-Identifier: Apache-2.0
/// @file RiskScore.cpp
#include "planning/RiskScore.h"

#include <algorithm>

namespace voxhap::planning {

RiskTerms riskScore(const TrajectoryReport& r, double needleMm, double deviceMaxN, double marginMm)
{
    RiskTerms t;
    t.breach = r.minClearanceMm <= 0.0 ? 1.0 : 0.0;
    t.tooShort = r.lengthMm > needleMm ? 1.0 : 0.0;
    t.boneObstacles = r.boneObstacles;
    t.overForce = r.peakForceN > deviceMaxN ? 1.0 : 0.0;
    for (const auto& c : r.clearances) t.proximity += std::max(0.0, 1.0 - c.minMm / marginMm);
    t.length = r.lengthMm / needleMm;
    t.force = r.peakForceN / deviceMaxN;
    t.total =
        100.0 * (t.breach + t.tooShort) + 10.0 * (t.boneObstacles + t.overForce) + t.proximity + t.length + t.force;
    return t;
}

} // namespace voxhap::planning
