// SPDX-License-Identifier: Apache-2.0
/// @file FusionReport.cpp
/// @brief Printing a FusionRecord.

#include "tools/FusionReport.h"

#include "core/Format.h"

namespace voxhap::tools {

void printFusionRecord(std::ostream& os, const volume::FusionRecord& r, const std::string& indent)
{
    os << indent << "started from     " << r.startedFrom << '\n';
    os << indent << "Mattes MI        " << fixed(r.metricGeometry, 4) << " at the header geometry, "
       << fixed(r.metricStart, 4) << " at the start, " << fixed(r.metricFinal, 4) << " registered\n";
    os << indent << "iterations       " << r.iterations << " (" << r.stopReason << ")\n";
    os << indent << "overlap          " << fixed(100.0 * r.overlapStart, 1)
       << " % of the MR body inside the CT at the start, " << fixed(100.0 * r.overlapFinal, 1) << " % registered\n";
    os << indent << "body surfaces    " << fixed(r.surfaceDistanceMm, 2) << " mm apart on average (limit "
       << fixed(r.surfaceLimitMm, 2) << " mm)\n";
    os << indent << "mr_from_ct (LPS mm, CT point -> MR point):\n";
    for (int row = 0; row < 4; ++row) {
        os << indent << "  ";
        for (int col = 0; col < 4; ++col) os << ' ' << fixed(r.mrFromCt(row, col), 6);
        os << '\n';
    }
    for (const auto& [channel, source] : r.channelSources) os << indent << channel << ": " << source << '\n';
    for (const std::string& w : r.warnings) os << indent << "warning: " << w << '\n';
}

} // namespace voxhap::tools
