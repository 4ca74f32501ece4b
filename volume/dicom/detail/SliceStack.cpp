// SPDX-License-Identifier: Apache-2.0
/// @file SliceStack.cpp
/// @brief Slice ordering along the normal and the uniform-grid checks.

#include "volume/dicom/detail/SliceStack.h"

#include "core/Errors.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace voxhap::volume {

SliceStackGeometry orderSlices(
    std::vector<SlicePlacement> slices, const Vec3d& normal, double toleranceMm, double directionTolerance)
{
    SliceStackGeometry g;
    g.normal = normal.normalized();
    const Vec3d n = g.normal;
    std::stable_sort(slices.begin(), slices.end(),
        [&n](const SlicePlacement& a, const SlicePlacement& b) { return a.position.dot(n) < b.position.dot(n); });
    g.slices = std::move(slices);
    if (g.slices.size() < 2) return g;

    std::vector<double> along;
    along.reserve(g.slices.size());
    for (const auto& s : g.slices) along.push_back(s.position.dot(n));
    std::vector<double> steps;
    for (std::size_t k = 1; k < along.size(); ++k) {
        const double d = along[k] - along[k - 1];
        if (d <= toleranceMm) {
            std::ostringstream os;
            os << "two slices at the same position along the normal (" << along[k]
               << " mm): a mixed or repeated series";
            throw ValueError(os.str());
        }
        steps.push_back(d);
    }
    // The lower median step: a few gaps or odd steps do not move it, jitter on
    // one slice counts once rather than twice (as against the smallest step),
    // and of two steps (three slices, one gap) it takes the smaller.
    std::vector<double> sorted = steps;
    const std::size_t mid = (sorted.size() - 1) / 2;
    std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(mid), sorted.end());
    g.step = sorted[mid];

    // Missing slices: a step that is a whole multiple (>= 2) of the median.
    // Non-uniform: any other step that differs from the median.
    std::ostringstream why;
    for (std::size_t k = 1; k < along.size(); ++k) {
        const double d = along[k] - along[k - 1];
        if (std::abs(d - g.step) <= toleranceMm) continue;
        g.uniform = false;
        const double ratio = d / g.step;
        const double whole = std::round(ratio);
        if (whole >= 2 && std::abs(d - whole * g.step) <= toleranceMm) {
            g.missingSlices += int(whole) - 1;
            if (why.tellp() == 0) {
                why << int(whole) - 1 << " slice(s) missing between positions " << along[k - 1] << " and " << along[k]
                    << " mm along the normal (step " << g.step << " mm)";
            }
        } else if (why.tellp() == 0) {
            why << "non-uniform slice spacing: step " << d << " mm between positions " << along[k - 1] << " and "
                << along[k] << " mm, usual step " << g.step << " mm";
        }
    }

    // Tilt: each position's drift off the line through the first along the normal.
    // A normal known only to the stored digits lets positions far along the
    // stack drift a little without any tilt: that much is tolerated too.
    double maxDrift = 0, maxExcess = -1;
    for (const auto& s : g.slices) {
        const Vec3d rel = s.position - g.slices.front().position;
        const double drift = (rel - rel.dot(n) * n).norm();
        maxDrift = std::max(maxDrift, drift);
        maxExcess = std::max(maxExcess, drift - (toleranceMm + std::abs(rel.dot(n)) * directionTolerance));
    }
    const Vec3d axis = g.slices.back().position - g.slices.front().position;
    g.tiltDeg = std::acos(std::clamp(axis.normalized().dot(n), -1.0, 1.0)) * 180.0 / kPi;
    if (maxExcess > 0) {
        g.tilted = true;
        g.uniform = false;
        std::ostringstream tilt;
        tilt << "gantry tilt: slice positions drift " << maxDrift << " mm off the slice normal (stack axis "
             << g.tiltDeg << " deg from the normal)";
        g.problem = tilt.str() + (why.tellp() == 0 ? "" : "; " + why.str());
    } else {
        g.problem = why.str();
    }
    return g;
}

} // namespace voxhap::volume
