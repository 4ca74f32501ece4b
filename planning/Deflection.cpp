// SPDX-License-Identifier: Apache-2.0
/// @file Deflection.cpp
/// @brief The bending needle pushed along a straight plan (physics.md §9.6).

#include "planning/Deflection.h"

#include "haptic/beam/BentNeedle.h"
#include "haptic/beam/Foundation.h"
#include "planning/Planner.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace voxhap::planning {

namespace {

/// The needle's hand pushed straight along entry → target, the hub on the line and
/// the needle along it, the straight tip from depth @p from to @p to.
class Push {
public:
    Push(const TrajectoryReport& path, const DeflectionOptions& o)
        : mEntry(path.entry), mTarget(path.target), mU((path.target - path.entry).normalized()),
          mDepth((path.target - path.entry).norm()), mO(o)
    {
    }
    double depth() const { return mDepth; }
    /// The needle straight at the entry, its track started there.
    void start(haptic::BentNeedle& needle) const
    {
        needle.reset();
        needle.setRoll(0.0);
        needle.update(hub(needle, 0.0), mU);
        needle.enter(mEntry);
    }
    /// Advance from @p from to @p to [mm] in steps of at most stepMm; returns where it stopped.
    double advance(haptic::BentNeedle& needle, double from, double to) const
    {
        const int steps = int(std::ceil((to - from) / mO.stepMm - 1e-9));
        for (int i = 1; i <= steps; ++i) needle.update(hub(needle, from + (to - from) * i / steps), mU);
        return std::max(from, to);
    }
    /// One solve with the hub held at depth @p d (after a turn: the tip's new heading).
    void hold(haptic::BentNeedle& needle, double d) const { needle.update(hub(needle, d), mU); }
    BevelChoice result(const haptic::BentNeedle& needle, double orientationDeg, double turnMm) const
    {
        BevelChoice c;
        c.orientationDeg = orientationDeg;
        c.turnDepthMm = turnMm;
        const Vec3d off = needle.tip() - mEntry;
        c.tipDeviationMm = (off - off.dot(mU) * mU).norm();
        c.tipToTargetMm = (needle.tip() - mTarget).norm();
        return c;
    }

private:
    Vec3d hub(const haptic::BentNeedle& needle, double d) const { return mEntry + (d - needle.params().lengthMm) * mU; }
    Vec3d mEntry, mTarget, mU;
    double mDepth;
    const DeflectionOptions& mO;
};

} // namespace

std::optional<DeflectionPrediction> predictDeflection(
    const Planner& planner, const TrajectoryReport& path, const DeflectionOptions& o)
{
    const haptic::Scene& scene = planner.scene();
    if (!scene.terms.bending.on) return std::nullopt;
    const Push push(path, o);
    DeflectionPrediction p;
    const double base = scene.needle.bevelOrientationDeg;
    std::vector<haptic::BentNeedle> ends; // each choice's needle at the target, in p.tried's order
    for (const double orientation : {base, base + 180.0}) {
        haptic::Needle n = scene.needle;
        n.bevelOrientationDeg = orientation;
        haptic::BeamParams params = haptic::BeamParams::fromNeedle(n);
        params.minNodeSpacingMm = std::max(params.minNodeSpacingMm, o.nodeSpacingMm);
        haptic::BentNeedle needle(
            params, haptic::makeLabelFoundation(planner.field()), haptic::bevelReferenceAxis(path.target - path.entry));
        push.start(needle);
        // One insertion without a turn; at each turn depth a copy branches off, is
        // turned half a turn and pushed on to the target (the prefix is shared).
        std::vector<BevelChoice> turned;
        std::vector<haptic::BentNeedle> branches;
        double d = 0.0;
        for (double turn = o.turnFromMm; turn < push.depth(); turn += o.turnEveryMm) {
            d = push.advance(needle, d, turn);
            haptic::BentNeedle branch(needle);
            branch.setRoll(kPi);
            push.hold(branch, d); // the turn is made in place, before the needle moves on
            (void)push.advance(branch, d, push.depth());
            turned.push_back(push.result(branch, orientation, turn));
            branches.push_back(std::move(branch));
        }
        (void)push.advance(needle, d, push.depth());
        p.tried.push_back(push.result(needle, orientation, kNoDepth));
        ends.push_back(std::move(needle));
        p.tried.insert(p.tried.end(), turned.begin(), turned.end());
        for (auto& b : branches) ends.push_back(std::move(b));
    }
    std::size_t best = 0;
    for (std::size_t i = 1; i < p.tried.size(); ++i) {
        if (p.tried[i].tipToTargetMm < p.tried[best].tipToTargetMm) best = i;
    }
    p.best = p.tried[best];
    const haptic::BentNeedle& chosen = ends[best];
    p.bentShaft.assign(chosen.shaft().begin(), chosen.shaft().end());
    for (int i = 0; i < chosen.track().count(); ++i) p.bentTrack.push_back(chosen.track().point(i));
    return p;
}

void predictDeflections(const Planner& planner, std::vector<TrajectoryReport>& paths, const DeflectionOptions& o)
{
    if (!planner.scene().terms.bending.on) return;
    tbb::parallel_for(std::size_t(0), std::min(paths.size(), o.maxPaths),
        [&](std::size_t i) { paths[i].deflection = predictDeflection(planner, paths[i], o); });
}

} // namespace voxhap::planning
