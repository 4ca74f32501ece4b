// SPDX-License-Identifier: Apache-2.0
/// @file Registration.cpp
/// @brief The pyramid, the orientation search, the stages and the checks.

#include "registration/Registration.h"

#include "core/Errors.h"
#include "core/Format.h"
#include "registration/LevelImage.h"
#include "registration/detail/MetricStage.h"
#include "registration/detail/SurfaceCheck.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <numeric>
#include <sstream>

#include <tbb/parallel_invoke.h>
#include <tbb/task_group.h>

namespace voxhap::registration {

using volume::Channel;
using volume::Volume;

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/// "Did not converge": the finest stage stopped at its iteration limit and the
/// metric still changed by more than this over its last kConvergenceWindow iterations.
constexpr double kConvergenceChange = 1e-4;
constexpr int kConvergenceWindow = 10;
/// "Barely moved": the metric's change from the start [chosen: a tenth of a
/// typical registration's gain on the phantoms and the porcine pair].
constexpr double kBarelyMoved = 1e-3;
/// Orientation search: iterations of each candidate's short run at the
/// coarsest level, and how many candidates are carried to the next level [chosen].
constexpr int kSearchIterations = 40;
constexpr int kSearchKept = 3;
constexpr int kRefineIterations = 60;
/// The optimiser's first step, in voxels of the level. The coarsest level
/// starts from the search or the headers and may have far to go; each finer
/// level starts from the coarser one's answer, which lies within a few tenths
/// of the coarser voxel, about half a voxel of its own [chosen: two voxels
/// there too took a fifth more iterations, on the phantoms 78 against 63 on
/// the torso, for the same error over four sample seeds].
constexpr double kCoarsestFirstStepVoxels = 2.0;
constexpr double kFinerFirstStepVoxels = 0.5;
/// Parallel lanes of the orientation search: the machine's two cores.
constexpr int kSearchLanes = 2;
/// Work units of each metric evaluation outside the search's lanes: two cores.
/// A constant, not the machine's core count: the sums' rounding follows the
/// count (MetricStage.cpp, OrderedMattes), and the answer should not follow
/// the machine.
constexpr int kStageUnits = 2;

/// The metric's window on CT numbers: air to dense cortical bone. Metal and
/// contrast beyond it would spread the histogram's bins over values no MR shows.
constexpr float kHuLow = -1000.0f, kHuHigh = 2000.0f;
/// The CT's body: above −500 HU, halfway between air (−1000) and fat (about
/// −100), as the CT segmentation finds it; its largest connected part.
constexpr float kBodyHu = -500.0f;
/// The MR's body: above a fifth of its bright tissue (the 90th percentile of
/// what the loader kept) [chosen]. The loader keeps what rises above the noise
/// floor (volume/mr/MrBackground.h); ghosts and the halo that parallel imaging
/// leaves beside a body pass that test at a tenth of tissue or less (the shared
/// porcine T2: a halo at 10–66 around tissue at 600–1000), while tissues differ
/// among themselves by less than five times (fat against muscle T1: three times;
/// on T1-weighted images, muscle against fat: two to three times).
constexpr float kMrTissueFraction = 0.2f;
constexpr double kMrBrightQuantile = 0.9;
/// The MR's window: its body's values up to this quantile (bright vessels and
/// fat suppression failures would otherwise take the upper bins).
constexpr double kMrQuantile = 0.995;

/// The bodies are opened by this radius before their largest part is taken:
/// table tops, the walls and lids of boxes and other positioning aids are
/// thinner than twice it, and join the body only through such parts [chosen].
constexpr double kOpeningMm = 3.0;

int openingVoxels(const LevelImage& l)
{
    return std::max(1, int(std::lround(kOpeningMm / l.geometry.spacing.minCoeff())));
}

/// The finest level samples the CT at its voxels' centres, the coarser
/// levels anywhere within them (StageSettings::jittered). Measured over five
/// sample seeds (RegistrationOptions::seed) against jittered samples at every
/// level, the mean error over the body: lumbar phantom 0.04–0.25 mm (mean
/// 0.14) against 0.26–0.33 (0.29), torso 0.08–0.27 (0.15) against 0.16–0.29
/// (0.23). The porcine pair's distance from elastix's pinned run kept its
/// spread over eight seeds (1.30–2.39 mm against 1.11–2.81; the mean of the
/// eight maps 1.55 and 1.54 mm from it).
constexpr bool kFinestAtCentres = true;

/// The metric's masks: the bodies grown by this much, so that the skin's edge
/// against the air (much of what aligns two scans) is sampled, while the air
/// beyond it is not [chosen: a few finest voxels].
constexpr double kMaskMarginMm = 3.0;

/// One resolution level of both images.
struct Level {
    LevelImage ct, mr;
    double voxelMm = 0; ///< the CT level's largest spacing
};

/// Block factors from one level to the next: double each axis still finer than @p targetMm.
Vec3i nextFactors(const Vec3d& spacing, double targetMm)
{
    Vec3i f;
    for (int a = 0; a < 3; ++a) f[a] = spacing[a] * 1.5 < targetMm ? 2 : 1;
    return f;
}

/// One modality's levels, finest last, each with its body: the same block
/// averages and openings for the CT and the MR; @p window clamps the finest
/// level's values and returns the body's threshold from them.
template <typename Window>
void buildLevels(LevelImage Level::*member, std::vector<Level>& levels, const Volume& v, Channel channel,
    const RegistrationOptions& o, Window window)
{
    LevelImage& fine = levels.back().*member;
    fine = blockAverage(v, channel, blockFactors(v.geometry().spacing, o.finestMm));
    const float body = window(fine);
    for (std::size_t l = levels.size() - 1; l-- > 0;) {
        const double target = o.finestMm * std::pow(2.0, double(levels.size() - 1 - l));
        const LevelImage& finer = levels[l + 1].*member;
        levels[l].*member = blockAverage(finer, nextFactors(finer.geometry.spacing, target));
    }
    for (Level& l : levels) bodyAbove(l.*member, body, openingVoxels(l.*member));
}

std::vector<Level> buildPyramid(const Volume& ct, const Volume& mr, const RegistrationOptions& o)
{
    std::vector<Level> levels(std::size_t(std::max(1, o.levels)));
    // The two modalities' levels are independent: side by side.
    tbb::parallel_invoke(
        [&] {
            // The CT's body by its calibrated numbers.
            buildLevels(&Level::ct, levels, ct, Channel::Hu, o, [](LevelImage& fine) {
                clampValues(fine, kHuLow, kHuHigh);
                return kBodyHu;
            });
        },
        [&] {
            // The MR's relative to its own bright tissue (kMrTissueFraction),
            // set once on the finest level.
            buildLevels(&Level::mr, levels, mr, movingChannel(mr), o, [](LevelImage& fine) {
                // Clamping keeps the values' order, so the bright quantile, below
                // the window's, is the same before it as after it.
                const std::vector<float> q = bodyQuantiles(fine, {kMrQuantile, kMrBrightQuantile});
                clampValues(fine, 0.0f, q[0]);
                return kMrTissueFraction * q[1];
            });
        });
    for (Level& l : levels) {
        l.voxelMm = l.ct.geometry.spacing.maxCoeff();
        if (l.ct.bodyCount() == 0) throw ValueError("registration: the CT holds no body (every voxel is air)");
        if (l.mr.bodyCount() == 0) throw ValueError("registration: the MR holds no body (every voxel is background)");
    }
    return levels;
}

int samplesAt(const RegistrationOptions& o, std::size_t level)
{
    if (o.samples.empty()) return 4000;
    return o.samples[std::min(level, o.samples.size() - 1)];
}

detail::StageSettings settingsAt(const RegistrationOptions& o, std::size_t level, const Level& l)
{
    detail::StageSettings s;
    s.jittered = !(kFinestAtCentres && level + 1 == std::size_t(std::max(1, o.levels)));
    s.iterations = o.iterations;
    s.samples = samplesAt(o, level);
    s.bins = o.bins;
    s.seed = o.seed + std::uint32_t(level);
    // First step two voxels of the coarsest level, half a voxel of each finer
    // one, last a fiftieth of the level's voxel.
    s.stepMm = (level == 0 ? kCoarsestFirstStepVoxels : kFinerFirstStepVoxels) * l.voxelMm;
    s.minimumStepMm = 0.02 * l.voxelMm;
    return s;
}

std::string axisName(int axis)
{
    static const char* names[] = {"L–R", "A–P", "S–I"};
    return names[axis];
}

} // namespace

Channel movingChannel(const Volume& mr)
{
    if (mr.has(Channel::T1)) return Channel::T1;
    if (mr.has(Channel::Intensity)) return Channel::Intensity;
    throw ValueError("registration: the MR has neither a t1 nor an intensity grid");
}

std::vector<Mat3d> axisTurns()
{
    std::vector<Mat3d> out{Mat3d::Identity()};
    std::vector<int> perm{0, 1, 2};
    do {
        for (int signs = 0; signs < 8; ++signs) {
            Mat3d r = Mat3d::Zero();
            for (int row = 0; row < 3; ++row) r(row, perm[std::size_t(row)]) = (signs >> row) & 1 ? -1.0 : 1.0;
            if (r.determinant() < 0 || r.isIdentity()) continue;
            out.push_back(r);
        }
    } while (std::next_permutation(perm.begin(), perm.end()));
    return out;
}

std::string describeRotation(const Mat3d& r)
{
    const double c = std::clamp((r.trace() - 1.0) / 2.0, -1.0, 1.0);
    const double angle = std::acos(c) * 180.0 / 3.14159265358979323846;
    if (angle < 1e-6) return "identity";
    Vec3d axis;
    if (angle > 179.999) {
        // R = 2·n·nᵀ − I: the axis is the column of R + I with the largest norm.
        const Mat3d m = r + Mat3d::Identity();
        int best = 0;
        for (int a = 1; a < 3; ++a) {
            if (m.col(a).norm() > m.col(best).norm()) best = a;
        }
        axis = m.col(best).normalized();
    } else {
        axis = Vec3d(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1)).normalized();
    }
    std::ostringstream os;
    os << std::lround(angle) << "° about ";
    for (int a = 0; a < 3; ++a) {
        if (std::abs(std::abs(axis[a]) - 1.0) < 1e-6) {
            os << (angle > 179.999 ? "" : (axis[a] > 0 ? "+" : "-")) << axisName(a);
            return os.str();
        }
    }
    os << "(" << fixed(axis.x(), 2) << ", " << fixed(axis.y(), 2) << ", " << fixed(axis.z(), 2) << ")";
    return os.str();
}

RegistrationResult registerMrToCt(const Volume& ct, const Volume& mr, const RegistrationOptions& o)
{
    const auto t0 = Clock::now();
    auto progress = [&](double f, std::string_view step) {
        if (o.progress) o.progress(f, step);
    };
    RegistrationResult result;
    if (!ct.has(Channel::Hu)) throw ValueError("registration: the fixed volume has no hu grid (is it a CT?)");
    progress(0.0, "pyramid");
    const std::vector<Level> levels = buildPyramid(ct, mr, o);
    const Level& finest = levels.back();
    // Each level's pair (ITK's images, masks and metrics) is built once, when
    // first used: the search's refinement and the stage of its level share one.
    std::vector<std::unique_ptr<detail::MetricPair>> pairs(levels.size());
    auto pairAt = [&](std::size_t l) -> const detail::MetricPair& {
        if (!pairs[l])
            pairs[l] = std::make_unique<detail::MetricPair>(levels[l].ct, levels[l].mr, kMaskMarginMm, kStageUnits);
        return *pairs[l];
    };
    const detail::MetricPair& finePair = pairAt(levels.size() - 1);
    const detail::StageSettings fineSettings = settingsAt(o, levels.size() - 1, finest);
    const Vec3d centre = finest.ct.bodyCentroid();
    try {
        result.metricGeometry = finePair.metricAt(AffineMap{}, centre, fineSettings);
    } catch (const ValueError&) {
        result.metricGeometry = 0.0; // the bodies do not meet at the header geometry: MI's worst value
    }

    // The start: the header geometry, or the best axis-aligned turn about the
    // CT body's centre, with the two bodies' centres brought together.
    AffineMap start;
    if (o.start == StartRule::Geometry) {
        result.startedFrom = "the header geometry (one frame of reference)";
    } else {
        const auto ts = Clock::now();
        progress(0.05, "orientation search");
        const Level& coarse = levels.front();
        const Vec3d ctCentre = coarse.ct.bodyCentroid();
        const Vec3d mrCentre = coarse.mr.bodyCentroid();
        detail::StageSettings s = settingsAt(o, 0, coarse);
        s.iterations = kSearchIterations;
        const std::vector<Mat3d> turns = axisTurns();
        std::vector<AffineMap> runs(turns.size());
        result.candidates.resize(turns.size());
        // The candidates are independent: kSearchLanes lanes run them, each
        // with its own copy of the coarsest level's ITK images (ITK's objects
        // are not shared between threads) and a single-threaded metric, so the
        // answer does not depend on the lanes' timing.
        tbb::task_group lanes;
        for (int lane = 0; lane < kSearchLanes; ++lane) {
            lanes.run([&, lane] {
                const detail::MetricPair coarsePair(coarse.ct, coarse.mr, kMaskMarginMm);
                for (std::size_t i = std::size_t(lane); i < turns.size(); i += kSearchLanes) {
                    OrientationCandidate& c = result.candidates[i];
                    c.rotation = turns[i];
                    c.name = describeRotation(turns[i]);
                    const AffineMap from = AffineMap::rotationAbout(turns[i], ctCentre, mrCentre - ctCentre);
                    try {
                        const detail::StageResult run = coarsePair.run(from, ctCentre, s);
                        c.metric = run.finalMetric;
                        runs[i] = run.map;
                    } catch (const ValueError&) {
                        c.metric = 0.0; // no overlap at all: the worst value mutual information takes
                        runs[i] = from;
                    }
                }
            });
        }
        lanes.wait();
        std::vector<std::size_t> order(result.candidates.size());
        std::iota(order.begin(), order.end(), std::size_t(0));
        std::stable_sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return result.candidates[a].metric < result.candidates[b].metric; });
        // The few best go one level finer; the best there is the start.
        const std::size_t nextLevel = std::min<std::size_t>(1, levels.size() - 1);
        const detail::MetricPair& refinePair = pairAt(nextLevel);
        detail::StageSettings rs = settingsAt(o, nextLevel, levels[nextLevel]);
        rs.iterations = kRefineIterations;
        double best = 1e300;
        std::size_t chosen = order.front();
        for (std::size_t n = 0; n < std::min<std::size_t>(kSearchKept, order.size()); ++n) {
            const std::size_t i = order[n];
            result.candidates[i].refined = true;
            try {
                const detail::StageResult run = refinePair.run(runs[i], ctCentre, rs);
                if (run.finalMetric < best) {
                    best = run.finalMetric;
                    chosen = i;
                    start = run.map;
                }
            } catch (const ValueError&) {
            }
        }
        if (best == 1e300) start = runs[chosen];
        result.startedFrom = "orientation search: " + result.candidates[chosen].name + " of 24 turns";
        result.searchSeconds = since(ts);
    }
    result.start = start;
    result.overlapStart = detail::overlapFraction(finest.ct, finest.mr, start);
    if (result.overlapStart < kMinimumOverlap) {
        throw ValueError("too little overlap: " + fixed(100.0 * result.overlapStart, 1) +
            " % of the MR body lies inside the CT after initialisation (from " + result.startedFrom + "; at least " +
            fixed(100.0 * kMinimumOverlap, 0) + " % is needed)");
    }
    result.metricStart = finePair.metricAt(start, centre, fineSettings);

    // The pyramid, coarse to fine: rigid, then affine when asked.
    AffineMap current = start;
    const detail::StageResult* last = nullptr;
    detail::StageResult fineRun;
    const std::vector<detail::StageKind> kinds = o.affine
        ? std::vector<detail::StageKind>{detail::StageKind::Rigid, detail::StageKind::Affine}
        : std::vector<detail::StageKind>{detail::StageKind::Rigid};
    for (detail::StageKind kind : kinds) {
        for (std::size_t l = 0; l < levels.size(); ++l) {
            progress(0.3 + 0.7 * double(l + 1) / double(levels.size() + 1),
                kind == detail::StageKind::Rigid ? "rigid" : "affine");
            const detail::MetricPair& pair = pairAt(l);
            detail::StageSettings s = settingsAt(o, l, levels[l]);
            s.kind = kind;
            fineRun = pair.run(current, centre, s);
            current = fineRun.map;
            last = &fineRun;
            StageReport rep;
            rep.kind = kind == detail::StageKind::Rigid ? "rigid" : "affine";
            rep.level = int(l);
            rep.voxelMm = levels[l].voxelMm;
            rep.iterations = fineRun.iterations;
            rep.startMetric = fineRun.startMetric;
            rep.finalMetric = fineRun.finalMetric;
            rep.stopReason = fineRun.stopReason;
            result.stages.push_back(rep);
            result.iterations += fineRun.iterations;
        }
    }
    result.mrFromCt = current;
    result.metricFinal = finePair.metricAt(current, centre, fineSettings);
    result.stopReason = last ? last->stopReason : "";
    if (last && last->hitIterationLimit && last->history.size() >= 2) {
        // Over the last kConvergenceWindow iterations, or all of them if fewer.
        const auto& h = last->history;
        const std::size_t window = std::min(std::size_t(kConvergenceWindow), h.size() - 1);
        const double change = std::abs(h.back() - h[h.size() - 1 - window]);
        if (change > kConvergenceChange) {
            result.converged = false;
            result.warnings.push_back("did not converge: the finest stage stopped at its limit of " +
                std::to_string(o.iterations) + " iterations while the metric still changed by " + fixed(change, 5) +
                " over its last " + std::to_string(window));
        }
    }
    if (std::abs(result.metricFinal - result.metricStart) < kBarelyMoved) {
        result.warnings.push_back("the metric barely moved from its start (" + fixed(result.metricStart, 4) + " to " +
            fixed(result.metricFinal, 4) + "): check the fusion views");
    }
    result.overlapFinal = detail::overlapFraction(finest.ct, finest.mr, current);

    // The body-surface check, against the MR's own voxel size. It runs on the
    // next coarser level: its limit, two MR voxel diagonals, spans several of
    // that level's voxels, and the distance map of the finest MR cost a fifth
    // of the registration.
    const Level& checked = levels[levels.size() > 1 ? levels.size() - 2 : 0];
    const detail::SurfaceDistance sd = detail::surfaceDistance(checked.ct, checked.mr, current);
    result.surfaceDistanceMm = sd.meanMm;
    result.surfacePoints = sd.points;
    result.surfaceLimitMm = 2.0 * mr.geometry().spacing.norm();
    if (sd.points == 0) {
        result.warnings.push_back("the body-surface check could not be made: no skin of the CT lies inside both "
                                  "fields of view away from their cut faces, or the MR's body fills its field of view");
    }
    result.seconds = since(t0);
    if (sd.points > 0 && sd.meanMm > result.surfaceLimitMm) {
        const std::string why = "failed the body-surface check: the CT's skin lies " + fixed(sd.meanMm, 1) +
            " mm on average from the registered MR body's surface (limit " + fixed(result.surfaceLimitMm, 1) +
            " mm, two MR voxel diagonals; " + std::to_string(sd.points) + " skin points)";
        if (!o.refuseFailedSurfaceCheck) {
            result.warnings.push_back(why);
            progress(1.0, "done");
            return result;
        }
        throw ValueError(why);
    }
    progress(1.0, "done");
    return result;
}

} // namespace voxhap::registration
