// SPDX-License-Identifier: Apache-2.0
/// @file ForcePlot.cpp
#include "tools/ForcePlot.h"

#include "bench/Gnuplot.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

namespace voxhap::tools {

bool plotForceDepth(const haptic::InsertionResult& r, const std::vector<haptic::Layer>& layers, const std::string& title,
                    const std::string& pngFile, std::string& why)
{
    const bench::PlotDir dir;
    const std::string data = (dir.path() / "force.dat").string();
    double maxDepth = 1.0, minDepth = 0.0;
    {
        std::ofstream o(data);
        for (const haptic::InsertionRow& row : r.rows) {
            o << row.depthMm << ' ' << row.axialN << ' ' << row.force.norm() << ' ' << row.plungerN << '\n';
            maxDepth = std::max(maxDepth, row.depthMm);
            minDepth = std::min(minDepth, row.depthMm);
        }
    }
    std::ostringstream g;
    g << "set title \"" << title << "\" noenhanced\n"
      << "set xlabel 'tip depth along the path [mm]'\nset ylabel 'force [N]'\nset y2label 'plunger force [N]'\n"
      << "set ytics nomirror\nset y2tics\nset grid\nset key top left opaque\nset xrange [" << minDepth << ':' << maxDepth << "]\n";
    // Layer bands, alternately shaded and named at the top.
    int n = 0;
    for (const haptic::Layer& l : layers) {
        if (l.startMm >= maxDepth || l.role == haptic::LayerRole::Air) continue;
        const double end = std::min(l.endMm, maxDepth);
        ++n;
        g << "set object " << n << " rect from " << l.startMm << ", graph 0 to " << end
          << ", graph 1 behind fillstyle solid 0.12 noborder fillcolor rgb '" << (n % 2 ? "#4a90d9" : "#d9a04a") << "'\n"
          << "set label " << n << " \"" << l.name << "\" at " << 0.5 * (l.startMm + end)
          << ", graph 0.97 right rotate by 90 font ',8' noenhanced\n";
    }
    // Events as dashed vertical lines; events at one depth share a line and a label.
    std::vector<std::pair<double, std::string>> marks;
    for (const haptic::Event& e : r.events) {
        if (e.type == haptic::EventType::SkinContact || e.type == haptic::EventType::CriticalClear) continue;
        if (!marks.empty() && std::abs(marks.back().first - e.depthMm) < 1e-9) marks.back().second += ", ";
        else marks.emplace_back(e.depthMm, "");
        marks.back().second += haptic::eventName(e.type);
    }
    int a = 0;
    for (const auto& [depth, text] : marks) {
        ++a;
        g << "set arrow " << a << " from " << depth << ", graph 0 to " << depth
          << ", graph 1 nohead dashtype 2 linecolor rgb '#aa0000'\n"
          << "set label " << (1000 + a) << " \"" << text << "\" at " << depth
          << ", graph 0.03 left rotate by 90 offset 0.7,0 font ',8' textcolor rgb '#aa0000' noenhanced\n";
    }
    g << "plot '" << data << "' using 1:2 with lines lw 2 title 'model resistance (axial)', '" << data
      << "' using 1:3 with lines lw 1.5 title 'rendered |F|', '" << data
      << "' using 1:4 axes x1y2 with lines dashtype 3 title 'plunger'";
    return bench::runGnuplot(dir, g.str(), pngFile, 1200, 700, why);
}

} // namespace voxhap::tools
