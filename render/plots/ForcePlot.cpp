// SPDX-License-Identifier: Apache-2.0
/// @file ForcePlot.cpp
#include "render/plots/ForcePlot.h"

#include "render/plots/Gnuplot.h"

#include <algorithm>
#include <fstream>
#include <sstream>

namespace voxhap::render {

bool plotForceDepth(const ForceTrace& trace, const std::string& pngFile, std::string& why)
{
    const PlotDir dir;
    const std::string data = (dir.path() / "force.dat").string();
    double maxDepth = 1.0, minDepth = 0.0;
    {
        std::ofstream o(data);
        for (const ForceTrace::Sample& s : trace.samples) {
            o << s.depthMm << ' ' << s.axialN << ' ' << s.renderedN << ' ' << s.plungerN << '\n';
            maxDepth = std::max(maxDepth, s.depthMm);
            minDepth = std::min(minDepth, s.depthMm);
        }
    }
    std::ostringstream g;
    g << "set title \"" << trace.title << "\" noenhanced\n"
      << "set xlabel 'tip depth along the path [mm]'\nset ylabel 'force [N]'\nset y2label 'plunger force [N]'\n"
      << "set ytics nomirror\nset y2tics\nset grid\nset key below\nset xrange [" << minDepth << ':' << maxDepth
      << "]\n";
    // Layer bands, alternately shaded and named at the top.
    int n = 0;
    for (const ForceTrace::Band& l : trace.layers) {
        if (l.startMm >= maxDepth) continue;
        const double end = std::min(l.endMm, maxDepth);
        ++n;
        g << "set object " << n << " rect from " << l.startMm << ", graph 0 to " << end
          << ", graph 1 behind fillstyle solid 0.12 noborder fillcolor rgb '" << (n % 2 ? "#4a90d9" : "#d9a04a")
          << "'\n"
          << "set label " << n << " \"" << l.name << "\" at " << 0.5 * (l.startMm + end)
          << ", graph 0.97 right rotate by 90 font ',8' noenhanced\n";
    }
    // Events as dashed vertical lines, named at the bottom.
    int a = 0;
    for (const ForceTrace::Mark& m : trace.events) {
        ++a;
        g << "set arrow " << a << " from " << m.depthMm << ", graph 0 to " << m.depthMm
          << ", graph 1 nohead dashtype 2 linecolor rgb '#aa0000'\n"
          << "set label " << (1000 + a) << " \"" << m.text << "\" at " << m.depthMm
          << ", graph 0.03 left rotate by 90 offset 0.7,0 font ',8' textcolor rgb '#aa0000' noenhanced\n";
    }
    g << "plot '" << data << "' using 1:2 with lines lw 2 title 'model resistance (axial)', '" << data
      << "' using 1:3 with lines lw 1.5 title 'rendered |F|', '" << data
      << "' using 1:4 axes x1y2 with lines dashtype 3 title 'plunger'";
    return runGnuplot(dir, g.str(), pngFile, 1200, 700, why);
}

} // namespace voxhap::render
