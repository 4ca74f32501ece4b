// SPDX-License-Identifier: Apache-2.0
/// @file Planner.cpp
/// @brief Path analysis: label runs (the exact voxel traversal of haptic/), the
/// clearances (Clearance.h), the force prediction (ForcePrediction.h), warnings
/// and the risk score (RiskScore.h).
#include "planning/Planner.h"

#include "haptic/shaft/LabelTrace.h"
#include "planning/Clearance.h"
#include "planning/ForcePrediction.h"
#include "planning/RiskScore.h"

#include "core/Errors.h"
#include "haptic/materials/MaterialField.h"
#include "segmentation/DistanceField.h"
#include "volume/Grids.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace voxhap::planning {

bool TrajectoryReport::hasWarning(const std::string& code) const
{
    return std::any_of(warnings.begin(), warnings.end(), [&](const Warning& w) { return w.code == code; });
}

struct Planner::Impl {
    std::unique_ptr<haptic::MaterialField> field;
    std::unique_ptr<haptic::LabelTracer> tracer;
    std::vector<std::pair<std::string, volume::Volume::GridConstPtr>> sdf;
    double toleranceMm = 0.25;
};

namespace {

std::string fmt(double x, int digits = 1)
{
    std::ostringstream s;
    s.setf(std::ios::fixed);
    s.precision(digits);
    s << x;
    return s.str();
}

} // namespace

std::uint64_t plannerWorkingBytes(const volume::Volume& v)
{
    // Two float grids over at most the labelled voxels: 4 bytes a value and about
    // 5 % for leaf masks and nodes (as segmentation counts its grids).
    const auto labels = volume::labelGrid(v);
    const double labelled = labels ? double(labels->activeVoxelCount()) : 0.0;
    return std::uint64_t(2.0 * 4.2 * labelled);
}

void checkMemoryCap(const volume::Volume& v, std::uint64_t capBytes)
{
    if (!capBytes) return;
    std::uint64_t input = 0;
    for (const volume::Channel c :
        {volume::Channel::Hu, volume::Channel::T1, volume::Channel::Intensity, volume::Channel::Label}) {
        if (v.has(c)) input += v.grid(c)->memUsage();
    }
    const std::uint64_t need = plannerWorkingBytes(v);
    if (input + need <= capBytes) return;
    const auto mib = [](std::uint64_t b) { return std::to_string(std::llround(double(b) / double(1 << 20))); };
    throw ValueError(v.metadata().source + ": planning needs about " + mib(need) +
        " MiB of working memory beside the volume's " + mib(input) + " MiB, over the memory cap of " + mib(capBytes) +
        " MiB");
}

Planner::Planner(std::shared_ptr<const volume::Volume> v, const volume::TissueTable& table, const haptic::Scene& scene,
    const PlanOptions& options)
    : mVolume(std::move(v)), mTable(table), mScene(scene), mOptions(options), mImpl(std::make_unique<Impl>())
{
    if (!mVolume || !mVolume->has(volume::Channel::Label)) {
        throw ValueError("planning: the volume has no tissue labels: segment it first (voxhap segment)");
    }
    if (!(options.profileStepMm > 0) || !(options.marginMm > 0) || options.minClearanceMm < 0 ||
        options.speedMmPerS < 0) {
        throw ValueError(
            "planning: profile step and margin must be positive, minimum clearance and speed not negative");
    }
    mSpeed = options.speedMmPerS > 0 ? options.speedMmPerS : scene.speedMmPerS;
    if (const auto* skin = table.find("skin")) mSkin = skin->id;

    haptic::MaterialOptions mo;
    mo.needs.damping = scene.terms.damping.on;
    mo.device = scene.device;
    mo.tipAreaMm2 = scene.needle.tipAreaMm2();
    mImpl->field = std::make_unique<haptic::MaterialField>(*mVolume, table, mo);
    mImpl->tracer = std::make_unique<haptic::LabelTracer>(*mImpl->field);
    // Distance fields: their band is the largest value they hold (DistanceField.h).
    const Vec3d vox = volume::fromVdb(mVolume->transform().voxelSize());
    mImpl->toleranceMm = options.clearanceToleranceMm > 0 ? options.clearanceToleranceMm : 0.5 * vox.minCoeff();
    for (const auto& t : table.tissues()) {
        if (auto g = mVolume->derived(segmentation::distanceFieldName(t.name))) {
            mImpl->sdf.emplace_back(t.name, g);
            const auto fg = openvdb::gridConstPtrCast<volume::FloatGrid>(g);
            if (fg) mBandMm = std::max(mBandMm, double(fg->background()));
        }
    }
}

Planner::~Planner() = default;

std::vector<std::string> Planner::criticalStructures() const
{
    std::vector<std::string> out;
    for (const auto& [name, g] : mImpl->sdf) out.push_back(name);
    return out;
}

const haptic::MaterialField& Planner::field() const { return *mImpl->field; }

int Planner::labelAt(const Vec3d& w) const
{
    const Vec3d ijk = mVolume->worldToIndex(w);
    return volume::labelGrid(*mVolume)->getConstAccessor().getValue(
        openvdb::Coord(int(std::lround(ijk.x())), int(std::lround(ijk.y())), int(std::lround(ijk.z()))));
}

std::vector<haptic::LabelRun> Planner::trace(
    const Vec3d& origin, const Vec3d& direction, double lengthMm, std::vector<haptic::DampingPiece>* damping) const
{
    return mImpl->tracer->trace(origin, direction, lengthMm, mScene.terms.damping.on ? damping : nullptr);
}

TrajectoryReport Planner::analyze(const Vec3d& entry, const Vec3d& target) const
{
    if (!entry.allFinite() || !target.allFinite()) throw ValueError("planning: entry and target must be finite");
    const double len = (target - entry).norm();
    if (!(len > 1e-6)) throw ValueError("planning: entry and target coincide");
    TrajectoryReport r;
    r.entry = entry, r.target = target, r.lengthMm = len;
    std::vector<haptic::DampingPiece> damping;
    auto runs = trace(entry, target - entry, len, &damping);
    return finish(std::move(r), std::move(runs), std::move(damping));
}

TrajectoryReport Planner::analyzeTraced(const Vec3d& entry, const Vec3d& target,
    const std::vector<haptic::LabelRun>& fromTarget, const std::vector<haptic::DampingPiece>& dampingFromTarget) const
{
    TrajectoryReport r;
    r.entry = entry, r.target = target, r.lengthMm = (target - entry).norm();
    std::vector<haptic::LabelRun> runs;
    runs.reserve(fromTarget.size());
    for (auto it = fromTarget.rbegin(); it != fromTarget.rend(); ++it) {
        runs.push_back({it->label, std::max(0.0, r.lengthMm - it->endMm), r.lengthMm - it->startMm});
    }
    std::vector<haptic::DampingPiece> damping;
    damping.reserve(dampingFromTarget.size());
    for (auto it = dampingFromTarget.rbegin(); it != dampingFromTarget.rend(); ++it) {
        if (it->startMm >= r.lengthMm) continue; // beyond the entry: outside the body
        damping.push_back({std::max(0.0, r.lengthMm - it->endMm), r.lengthMm - it->startMm, it->beta});
    }
    return finish(std::move(r), std::move(runs), std::move(damping));
}

TrajectoryReport Planner::finish(
    TrajectoryReport r, std::vector<haptic::LabelRun> runs, std::vector<haptic::DampingPiece> damping) const
{
    const int targetLabel = labelAt(r.target);
    if (const auto* t = mTable.find(targetLabel)) r.targetTissue = t->name;

    // Tissue segments, and the bone met on the way (§1.3: the tip stops on rigid layers).
    r.segments.reserve(runs.size());
    for (const auto& run : runs) {
        TissueSegment s;
        s.label = run.label;
        s.startMm = run.startMm;
        s.endMm = std::min(run.endMm, r.lengthMm);
        if (const auto* t = mTable.find(run.label))
            s.tissue = t->name, s.critical = t->critical, s.rigid = t->rigid;
        else
            s.tissue = "label " + std::to_string(run.label);
        if (s.endMm > s.startMm) r.segments.push_back(std::move(s));
    }
    // Bone entries: each maximal run of rigid segments. The last one counts as the
    // target's own bone (the access to a vertebral target) when the target lies in it
    // or directly beyond it with only non-bone target tissue between (a lesion inside
    // the body); every other entry is an obstacle the needle must pass.
    int lastGroupEnd = -1;
    std::vector<std::pair<int, int>> groups; // [first, last] segment indices
    for (int i = 0; i < int(r.segments.size()); ++i) {
        if (!r.segments[std::size_t(i)].rigid) continue;
        if (lastGroupEnd == i - 1 && !groups.empty())
            groups.back().second = i;
        else
            groups.emplace_back(i, i);
        lastGroupEnd = i;
    }
    r.boneEntries = int(groups.size());
    if (!groups.empty()) r.firstBoneMm = r.segments[std::size_t(groups.front().first)].startMm;
    r.boneObstacles = r.boneEntries;
    if (!groups.empty()) {
        const int last = groups.back().second, n = int(r.segments.size());
        bool own = last == n - 1;
        if (!own) {
            own = true; // only target tissue after the group
            for (int i = last + 1; i < n; ++i) own = own && r.segments[std::size_t(i)].label == targetLabel;
        }
        if (own) --r.boneObstacles;
    }

    // Clearances along the needle's axis, entry to target.
    for (const auto& [name, grid] : mImpl->sdf) {
        Clearance c = clearanceAlong(grid, r.entry, r.target, mImpl->toleranceMm, mBandMm);
        c.tissue = name;
        if (c.minMm < r.minClearanceMm) r.minClearanceMm = c.minMm, r.nearestStructure = name;
        r.clearances.push_back(std::move(c));
    }
    // A critical label on the path is a breach even where no distance field exists.
    for (const auto& s : r.segments) {
        if (s.critical && mImpl->sdf.end() == std::find_if(mImpl->sdf.begin(), mImpl->sdf.end(), [&](const auto& p) {
                return p.first == s.tissue;
            })) {
            r.clearances.push_back({s.tissue, -0.5 * s.lengthMm(), 0.5 * (s.startMm + s.endMm), false});
            if (r.clearances.back().minMm < r.minClearanceMm)
                r.minClearanceMm = r.clearances.back().minMm, r.nearestStructure = s.tissue;
        }
    }

    // Predicted force at the planning speed from the scene's model.
    ForceModelInputs in;
    const std::vector<haptic::Layer> layers = haptic::layersFromRuns(runs, mTable, mScene.recipe);
    in.layers = &layers;
    in.terms = mScene.terms;
    in.needle = mScene.needle;
    in.device = mScene.device;
    in.speedMmPerS = mSpeed;
    in.stepMm = mOptions.profileStepMm;
    const DampingLine line(std::move(damping));
    in.damping = &line;
    ForceProfile fp = predictForce(in, r.lengthMm);
    r.speedMmPerS = mSpeed;
    r.force = std::move(fp.samples);
    r.peakForceN = fp.peakN;
    r.peakDepthMm = fp.peakDepthMm;
    r.contactMm = fp.contactMm;

    // Warnings.
    for (const auto& c : r.clearances) {
        if (c.minMm <= 0.0) {
            r.warnings.push_back(
                {"critical_breach", "the path enters the " + c.tissue + " (at " + fmt(c.atDepthMm) + " mm)"});
        } else if (c.minMm < mOptions.minClearanceMm) {
            r.warnings.push_back({"clearance_below_minimum",
                "the path passes " + fmt(c.minMm) + " mm from the " + c.tissue + " (minimum " +
                    fmt(mOptions.minClearanceMm) + " mm)"});
        }
    }
    // The device renders the model's force times the scene's force_scale:
    // its limit is the model's divided by the scale.
    const double scale = mScene.terms.renderScale;
    const double modelLimitN = mScene.device.maxForceN / scale;
    if (r.peakForceN > modelLimitN) {
        r.warnings.push_back({"force_above_device_limit",
            "predicted peak " + fmt(r.peakForceN, 2) + " N at " + fmt(r.peakDepthMm) + " mm" +
                (scale != 1.0 ? " (" + fmt(r.peakForceN * scale, 2) + " N at the scene's force scale)" : "") +
                " exceeds the " + mScene.device.name + "'s " + fmt(mScene.device.maxForceN, 2) + " N"});
    }
    if (r.lengthMm > mScene.needle.lengthMm) {
        r.warnings.push_back({"needle_too_short",
            "the path is " + fmt(r.lengthMm) + " mm, the needle " + fmt(mScene.needle.lengthMm) + " mm"});
    }
    if (r.boneObstacles > 0) {
        r.warnings.push_back({"bone_before_target",
            std::to_string(r.boneObstacles) + " bone crossing(s) before the target, the first at " +
                fmt(r.firstBoneMm) + " mm"});
    }
    r.risk =
        riskScore(r, mScene.needle.lengthMm, mScene.device.maxForceN / mScene.terms.renderScale, mOptions.marginMm);
    return r;
}

} // namespace voxhap::planning
