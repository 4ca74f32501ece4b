// SPDX-License-Identifier: Apache-2.0
/// @file Guide.cpp
#include "tools/Guide.h"

#include "tools/Cli.h"

#include "core/Errors.h"
#include "planning/PlanFile.h"

#include <iomanip>
#include <sstream>

namespace voxhap::tools {

void addGuideOptions(CLI::App& cmd, GuideOptions& o)
{
    cmd.add_option("--guide", o.file,
        "Guidance toward a planned line (novice mode): a report.json or paths.mrk.json from `voxhap plan`, or a "
        "plan.json; the scene's terms.guidance parameters apply, else the defaults");
    cmd.add_option("--guide-path", o.path, "Which planned path of --guide: the report's rank or the markups' Line (1)")
        ->check(CLI::Range(1, 1000000));
}

std::optional<haptic::GuideLine> guideLine(const GuideOptions& o, const CLI::App& cmd)
{
    if (o.file.empty()) {
        if (cmd.count("--guide-path")) throw UsageError("--guide-path needs --guide FILE");
        return std::nullopt;
    }
    const planning::Plan plan = planning::loadPlan(o.file);
    if (o.path > int(plan.paths.size())) {
        throw ValueError(o.file + ": paths: no path " + std::to_string(o.path) + " (the file has " +
            std::to_string(plan.paths.size()) + ")");
    }
    const planning::PlannedPath& p = plan.paths[std::size_t(o.path - 1)];
    return haptic::GuideLine{p.entry, p.target};
}

std::string guideDescription(const GuideOptions& o, const haptic::GuideLine& line)
{
    std::ostringstream s;
    s << std::fixed << std::setprecision(1) << "path " << o.path << " of " << o.file << ": (" << line.entry.x() << ", "
      << line.entry.y() << ", " << line.entry.z() << ") -> (" << line.target.x() << ", " << line.target.y() << ", "
      << line.target.z() << ") mm";
    return s.str();
}

} // namespace voxhap::tools
