// SPDX-License-Identifier: Apache-2.0
/// @file Search.cpp
#include "planning/Search.h"

#include "core/Errors.h"

#include <Eigen/Geometry>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace voxhap::planning {

std::vector<Vec3d> directionGrid(const Vec3d& axis, double maxAngleDeg, double stepDeg)
{
    if (!(axis.norm() > 0) || !axis.allFinite())
        throw ValueError("search: the reference direction must be a non-zero vector");
    if (!(stepDeg > 0) || !(maxAngleDeg >= 0) || maxAngleDeg > 180) {
        throw ValueError("search: the grid step must be positive and the maximum angle in [0, 180] degrees");
    }
    const Vec3d w = axis.normalized();
    // Any two unit vectors orthogonal to w and to each other.
    const Vec3d a = (std::abs(w.x()) < 0.9 ? Vec3d::UnitX() : Vec3d::UnitY()).cross(w).normalized();
    const Vec3d b = w.cross(a);
    std::vector<Vec3d> dirs{w};
    const double step = degToRad(stepDeg);
    for (int ring = 1; ring * stepDeg <= maxAngleDeg + 1e-9; ++ring) {
        const double theta = ring * step;
        const int n = std::max(1, int(std::lround(2.0 * kPi * std::sin(theta) / step)));
        for (int k = 0; k < n; ++k) {
            const double phi = 2.0 * kPi * (k + 0.5 * (ring % 2)) / n; // staggered rings
            dirs.push_back(std::cos(theta) * w + std::sin(theta) * (std::cos(phi) * a + std::sin(phi) * b));
        }
    }
    return dirs;
}

std::vector<std::size_t> paretoFront(const std::vector<TrajectoryReport>& c, double bandMm)
{
    const auto clearance = [&](std::size_t i) {
        return bandMm > 0 ? std::min(c[i].minClearanceMm, bandMm) : c[i].minClearanceMm;
    };
    const auto dominates = [&](std::size_t j, std::size_t i) {
        const double ci = clearance(i), cj = clearance(j);
        const bool noWorse = cj >= ci && c[j].lengthMm <= c[i].lengthMm && c[j].peakForceN <= c[i].peakForceN;
        return noWorse && (cj > ci || c[j].lengthMm < c[i].lengthMm || c[j].peakForceN < c[i].peakForceN);
    };
    // Best clearance first (ties: shorter, then weaker): a candidate's dominators all come
    // before it, and since domination is transitive one of them is on the front already,
    // so each candidate is checked against the front only, not against all others.
    std::vector<std::size_t> order(c.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        if (clearance(a) != clearance(b)) return clearance(a) > clearance(b);
        if (c[a].lengthMm != c[b].lengthMm) return c[a].lengthMm < c[b].lengthMm;
        return c[a].peakForceN < c[b].peakForceN;
    });
    std::vector<std::size_t> front;
    for (std::size_t i : order) {
        if (std::none_of(front.begin(), front.end(), [&](std::size_t j) { return dominates(j, i); }))
            front.push_back(i);
    }
    std::sort(front.begin(), front.end());
    return front;
}

namespace {

enum class Outcome {
    NoExit,
    NotSkin,
    OutsideBox,
    Breach,
    Clearance,
    Bone,
    TooLong,
    Feasible
};

struct Slot {
    Outcome outcome = Outcome::NoExit;
    bool analysed = false;
    TrajectoryReport report;
};

} // namespace

SearchResult search(const Planner& planner, const Vec3d& target, const SearchConstraints& k, const SearchOptions& o)
{
    const auto start = std::chrono::steady_clock::now();
    if (!target.allFinite()) throw ValueError("search: the target must be finite");
    if (o.top < 1) throw ValueError("search: top must be at least 1");
    const double maxLen = k.maxLengthMm > 0 ? k.maxLengthMm : planner.scene().needle.lengthMm;
    if (planner.labelAt(target) == 0) throw ValueError("search: the target lies outside the body (air)");
    const std::vector<Vec3d> dirs = directionGrid(k.reference, k.maxAngleDeg, o.stepDeg);
    const int skin = k.skinEntry ? planner.skinLabel() : -1;

    std::vector<Slot> slots(dirs.size());
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, dirs.size(), 8), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                Slot& s = slots[i];
                // Outward from the target: the last tissue run ends where the body does.
                // Tracing a little past the maximum tells "ends in reach" from "goes on".
                const double reach = maxLen + 1.0;
                std::vector<haptic::DampingPiece> damping;
                const auto runs = planner.trace(target, dirs[i], reach, &damping);
                if (runs.empty() || runs.back().endMm >= reach - 1e-6) continue; // NoExit
                if (skin >= 0 && runs.back().label != skin) {
                    s.outcome = Outcome::NotSkin;
                    continue;
                }
                const Vec3d entry = target + runs.back().endMm * dirs[i];
                if (k.entryBox && !k.entryBox->contains(entry)) {
                    s.outcome = Outcome::OutsideBox;
                    continue;
                }
                s.report = planner.analyzeTraced(entry, target, runs, damping);
                s.analysed = true;
                const TrajectoryReport& r = s.report;
                if (r.minClearanceMm <= 0.0)
                    s.outcome = Outcome::Breach;
                else if (r.minClearanceMm < planner.options().minClearanceMm)
                    s.outcome = Outcome::Clearance;
                else if (!k.allowBoneObstacles && r.boneObstacles > 0)
                    s.outcome = Outcome::Bone;
                else if (r.lengthMm > maxLen)
                    s.outcome = Outcome::TooLong;
                else
                    s.outcome = Outcome::Feasible;
            }
        });

    SearchResult out;
    out.maxLengthMm = maxLen;
    out.counts.directions = std::int64_t(dirs.size());
    std::vector<TrajectoryReport> feasible;
    for (Slot& s : slots) {
        out.counts.analysed += s.analysed;
        switch (s.outcome) {
        case Outcome::NoExit:
            ++out.counts.noSkinExit;
            break;
        case Outcome::NotSkin:
            ++out.counts.notSkin;
            break;
        case Outcome::OutsideBox:
            ++out.counts.outsideBox;
            break;
        case Outcome::Breach:
            ++out.counts.breach;
            break;
        case Outcome::Clearance:
            ++out.counts.clearance;
            break;
        case Outcome::Bone:
            ++out.counts.bone;
            break;
        case Outcome::TooLong:
            ++out.counts.tooLong;
            break;
        case Outcome::Feasible:
            feasible.push_back(std::move(s.report));
            break;
        }
    }
    out.counts.feasible = std::int64_t(feasible.size());
    for (std::size_t i : paretoFront(feasible, planner.distanceBandMm())) out.pareto.push_back(feasible[i]);
    std::sort(out.pareto.begin(), out.pareto.end(),
        [](const auto& a, const auto& b) { return a.minClearanceMm > b.minClearanceMm; });
    std::sort(
        feasible.begin(), feasible.end(), [](const auto& a, const auto& b) { return a.risk.total < b.risk.total; });
    if (feasible.size() > std::size_t(o.top)) feasible.resize(std::size_t(o.top));
    out.ranked = std::move(feasible);
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}

} // namespace voxhap::planning
