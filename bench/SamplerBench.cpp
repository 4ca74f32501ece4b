// SPDX-License-Identifier: Apache-2.0
/// @file SamplerBench.cpp
/// @brief Workloads, references, interleaved timing and the report.

#include "bench/SamplerBench.h"

#include "bench/BlockDdaPeer.h"
#include "bench/DenseField.h"
#include "bench/PlaneCrossingSum.h"
#include "bench/VtkProbe.h"
#include "core/Errors.h"
#include "haptic/materials/MaterialLaws.h"
#include "haptic/shaft/ShaftIntegration.h"
#include "haptic/shaft/TrajectoryProfile.h"
#include "phantoms/Phantoms.h"
#include "render/plots/Gnuplot.h"
#include "segmentation/Segmentation.h"
#include "volume/Grids.h"
#include "volume/VolumeFile.h"
#include "volume/mr/T1Normalisation.h"

#include <Eigen/Geometry>
#include <openvdb/tools/ChangeBackground.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <thread>

namespace voxhap::bench {

namespace {

using haptic::Segment;
using haptic::ShaftIntegral;
using Clock = std::chrono::steady_clock;

/// R1 workload layers: 100 mm deep so that 100 mm shafts stay inside at any tilt.
const std::vector<volume::SlabLayer> kSlabLayers{
    {"skin", 2.0}, {"fat", 18.0}, {"muscle", 40.0}, {"interspinous_ligament", 20.0}, {"fat", 20.0}};

/// β per tissue for the workloads: physics.md §5.4 fitted values [N·s/mm²].
double workloadBeta(const std::string& tissue)
{
    static const std::map<std::string, double> kBeta{{"skin", 8152e-6}, {"fat", 3696e-6}, {"muscle", 8152e-6},
        {"interspinous_ligament", 16304e-6}, {"ligamentum_flavum", 16304e-6}, {"cancellous_bone", 0.0},
        {"cortical_bone", 0.0}};
    const auto it = kBeta.find(tissue);
    return it == kBeta.end() ? 8152e-6 : it->second; // other soft tissue as muscle
}

struct Workload {
    std::string name;
    std::unique_ptr<volume::Volume> volume;
    std::unique_ptr<haptic::MaterialField> field;
    std::vector<std::vector<Segment>> paths;           ///< per path, the shafts at increasing depth
    std::function<double(const Segment&)> pcReference; ///< exact ∫β of the voxel reading (closed form if any)
    std::string pcReferenceName;
    double voxelMm = 0.5;
    /// More paths of the same kind (count, depths per path): the fidelity sample.
    std::function<std::vector<std::vector<Segment>>(int, int, std::mt19937&)> morePaths;
};

std::unique_ptr<haptic::MaterialField> fieldWithWorkloadBeta(const volume::Volume& v)
{
    const auto& table = volume::TissueTable::builtin();
    const auto labels = volume::labelGrid(v);
    auto beta = volume::FloatGrid::create(0.0f);
    beta->setTree(std::make_shared<volume::FloatGrid::TreeType>(labels->tree(), 0.0f, openvdb::TopologyCopy()));
    auto acc = labels->getConstAccessor();
    for (auto it = beta->tree().beginValueOn(); it; ++it) {
        it.setValue(float(workloadBeta(table.at(acc.getValue(it.getCoord())).name)));
    }
    beta->setTransform(labels->transform().copy());
    return std::make_unique<haptic::MaterialField>(beta, labels, table);
}

/// Shafts from @p entry along directions tilted 0..60° from @p inward, depths up to 100 mm.
std::vector<std::vector<Segment>> makePaths(
    const Vec3d& entry, const Vec3d& inward, const SamplerBenchOptions& o, std::mt19937& rng, double jitterMm)
{
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<std::vector<Segment>> paths;
    const Vec3d side = inward.unitOrthogonal();
    for (int p = 0; p < o.paths; ++p) {
        const double tilt = degToRad(60.0) * double(p) / std::max(1, o.paths - 1);
        const double azimuth = 2.0 * kPi * unit(rng);
        const Vec3d axis = Eigen::AngleAxisd(azimuth, inward) * side;
        const Vec3d u = Eigen::AngleAxisd(tilt, axis) * inward;
        const Vec3d e = entry + jitterMm * Vec3d(unit(rng) - 0.5, 0.0, unit(rng) - 0.5);
        std::vector<Segment> shafts;
        for (int d = 1; d <= o.depths; ++d) shafts.push_back({e, e + (100.0 * d / o.depths) * u});
        paths.push_back(std::move(shafts));
    }
    return paths;
}

/// makePaths from @p entry, inward along −y, as a path maker for any count and depth.
std::function<std::vector<std::vector<Segment>>(int, int, std::mt19937&)> pathsFrom(
    const Vec3d& entry, const SamplerBenchOptions& o, double jitterMm)
{
    return [entry, o, jitterMm](int count, int depths, std::mt19937& r) {
        SamplerBenchOptions more = o;
        more.paths = count;
        more.depths = depths;
        return makePaths(entry, Vec3d(0, -1, 0), more, r, jitterMm);
    };
}

/// A workload on a phantom model at the options' spacing, β from workloadBeta().
Workload phantomWorkload(const std::string& name, const volume::PhantomModel& model, const SamplerBenchOptions& o)
{
    Workload w;
    w.name = name;
    w.voxelMm = o.spacingMm;
    volume::GridSpec grid;
    grid.spacing = Vec3d::Constant(o.spacingMm);
    w.volume = std::make_unique<volume::Volume>(volume::makePhantom(model, grid, volume::TissueTable::builtin()));
    w.field = fieldWithWorkloadBeta(*w.volume);
    return w;
}

Workload slabWorkload(const SamplerBenchOptions& o, std::mt19937& rng)
{
    volume::SlabParams p;
    p.layers = kSlabLayers;
    p.halfWidthMm = 95.0; // a 60° shaft of 100 mm drifts 87 mm sideways
    Workload w = phantomWorkload("slab", volume::slabModel(p, volume::TissueTable::builtin()), o);
    w.morePaths = pathsFrom(Vec3d::Zero(), o, o.spacingMm);
    w.paths = w.morePaths(o.paths, o.depths, rng);
    // physics.md §7 R1 closed form, depth from the surface y = 0; β as the grid stores it (float).
    w.pcReference = [](const Segment& s) {
        const Vec3d d = s.tip - s.entry;
        const double length = d.norm(), cosT = -d.y() / length;
        double z = 0.0, sum = 0.0;
        for (const auto& l : kSlabLayers) {
            sum += double(float(workloadBeta(l.tissue))) * std::clamp(length * cosT - z, 0.0, l.thicknessMm) / cosT;
            z += l.thicknessMm;
        }
        return sum;
    };
    w.pcReferenceName = "R1 closed form";
    return w;
}

Workload torsoWorkload(const SamplerBenchOptions& o, std::mt19937& rng)
{
    Workload w = phantomWorkload("torso", volume::torsoModel(volume::TorsoParams{}, volume::TissueTable::builtin()), o);
    // From the posterior skin 40 mm left of the midline, inward and tilted.
    w.morePaths = pathsFrom(Vec3d(40.0, -8.0, 0.0), o, 10.0);
    w.paths = w.morePaths(o.paths, o.depths, rng);
    auto exact = std::shared_ptr<haptic::ShaftIntegrator>(
        haptic::makeIntegrator(*w.field, {haptic::Strategy::ExactVoxel, 0.1, false}));
    w.pcReference = [exact](const Segment& s) {
        ShaftIntegral r;
        exact->integrate(s, r);
        return r.dampingIntegral;
    };
    w.pcReferenceName = "exact voxel traversal (validated against R1/R5 in the tests)";
    return w;
}

/// Random insertion paths through the body of a real volume: a target at a
/// random active voxel of @p body, a direction uniform on the sphere, the entry
/// where the line last leaves the body within 150 mm behind the target (the
/// skin, marching back in 0.5 mm steps); shafts from there up to 100 mm.
std::vector<std::vector<Segment>> bodyPaths(const volume::FloatGrid& body, int count, int depths, std::mt19937& rng)
{
    std::vector<const volume::FloatGrid::TreeType::LeafNodeType*> leaves;
    for (auto it = body.tree().cbeginLeaf(); it; ++it) leaves.push_back(&*it);
    if (leaves.empty()) throw ValueError("bench sampler: the volume has no active voxels");
    std::uniform_int_distribution<std::size_t> pickLeaf(0, leaves.size() - 1);
    std::uniform_int_distribution<openvdb::Index> pickVoxel(0, 511);
    std::normal_distribution<double> gauss(0.0, 1.0);
    auto acc = body.getConstAccessor();
    const auto inside = [&](const Vec3d& p) {
        return acc.isValueOn(openvdb::Coord::round(body.transform().worldToIndex(volume::toVdb(p))));
    };
    std::vector<std::vector<Segment>> paths;
    while (int(paths.size()) < count) {
        const auto* leaf = leaves[pickLeaf(rng)];
        const openvdb::Index n = pickVoxel(rng);
        if (!leaf->isValueOn(n)) continue;
        const Vec3d target = volume::fromVdb(body.transform().indexToWorld(leaf->offsetToGlobalCoord(n)));
        Vec3d u(gauss(rng), gauss(rng), gauss(rng));
        if (!(u.norm() > 1e-9)) continue;
        u.normalize();
        Vec3d entry = target;
        for (double back = 0.5; back <= 150.0; back += 0.5) {
            if (inside(target - back * u)) entry = target - back * u;
        }
        std::vector<Segment> shafts;
        for (int d = 1; d <= depths; ++d) shafts.push_back({entry, entry + (100.0 * d / depths) * u});
        paths.push_back(std::move(shafts));
    }
    return paths;
}

/// bodyPaths through @p body, as a path maker for any count and depth.
std::function<std::vector<std::vector<Segment>>(int, int, std::mt19937&)> pathsThroughBody(
    volume::FloatGrid::ConstPtr body)
{
    return [body](int count, int depths, std::mt19937& r) { return bodyPaths(*body, count, depths, r); };
}

/// The shared CT: loaded and segmented as `voxhap segment` does, β per label
/// from the tissue table through the mapping layer (MaterialField).
Workload ctWorkload(const SamplerBenchOptions& o, std::mt19937& rng, const Progress& progress)
{
    Workload w;
    w.name = "ct";
    progress(-1.0, "loading and segmenting the CT " + o.ctDir.string());
    w.volume = std::make_unique<volume::Volume>(volume::loadVolume(o.ctDir));
    segmentation::segment(*w.volume, volume::TissueTable::builtin());
    w.field =
        std::make_unique<haptic::MaterialField>(*w.volume, volume::TissueTable::builtin(), haptic::MaterialOptions{});
    w.voxelMm = w.volume->geometry().spacing.minCoeff();
    w.morePaths = pathsThroughBody(openvdb::gridConstPtrCast<volume::FloatGrid>(w.field->damping()));
    w.paths = w.morePaths(o.paths, o.depths, rng);
    return w;
}

/// The shared T1-weighted MR: air around the head inactive (MrBackground.h),
/// intensities normalised to T1 by the per-scan rule (physics.md §5.1) even
/// though it is a head (the loader refuses that for physics; here it only makes
/// a T1 field that changes voxel by voxel), then β = C1·e^(C2·T1) per voxel
/// (Kyung Eq. 4, physics.md §5.4, 3 T fit).
Workload mrWorkload(const SamplerBenchOptions& o, std::mt19937& rng, const Progress& progress)
{
    Workload w;
    w.name = "mr";
    progress(-1.0, "loading the MR " + o.mrDir.string());
    w.volume = std::make_unique<volume::Volume>(volume::loadVolume(o.mrDir));
    volume::Volume& v = *w.volume;
    if (!v.grid(volume::Channel::T1)) {
        if (!v.grid(volume::Channel::Intensity)) throw ValueError("bench sampler: " + o.mrDir.string() + " is not MR");
        v.setGrid(volume::Channel::T1, std::const_pointer_cast<openvdb::GridBase>(v.grid(volume::Channel::Intensity)));
        v.removeGrid(volume::Channel::Intensity);
        volume::applyT1wNormalisation(v,
            volume::fitT1wNormalisation(
                v, volume::TissueTable::builtin(), volume::FieldStrength::T3, o.mrDir.string()));
    }
    const auto t1 = openvdb::gridConstPtrCast<volume::FloatGrid>(v.grid(volume::Channel::T1));
    const haptic::T1DampingLaw law = haptic::t1DampingLaw(volume::FieldStrength::T3);
    auto beta = t1->deepCopy();
    // Air is inactive and carries no damping: zero every inactive value the walk could read.
    for (auto it = beta->tree().beginValueOn(); it; ++it) it.setValue(float(law.dampingNsPerMm2(double(*it))));
    for (auto it = beta->tree().beginValueOff(); it; ++it) it.setValue(0.0f);
    openvdb::tools::changeBackground(beta->tree(), 0.0f);
    w.field = std::make_unique<haptic::MaterialField>(beta, nullptr, volume::TissueTable::builtin());
    w.voxelMm = v.geometry().spacing.minCoeff();
    w.morePaths = pathsThroughBody(beta);
    w.paths = w.morePaths(o.paths, o.depths, rng);
    return w;
}

/// The exact voxel traversal as the reference of the voxel reading on real
/// data (validated against closed forms R1/R5 in the tests).
void exactVoxelReference(Workload& w)
{
    auto exact = std::shared_ptr<haptic::ShaftIntegrator>(
        haptic::makeIntegrator(*w.field, {haptic::Strategy::ExactVoxel, 0.1, false}));
    w.pcReference = [exact](const Segment& s) {
        ShaftIntegral r;
        exact->integrate(s, r);
        return r.dampingIntegral;
    };
    w.pcReferenceName = "exact voxel traversal (validated against R1/R5 in the tests)";
}

struct Config {
    std::string name, reading;
    /// Evaluate all shafts of one path into out (one value per shaft).
    std::function<void(const std::vector<Segment>&, std::vector<double>&)> run;
    /// Untimed preparation before a path's batch (the profile's lock), if any.
    std::function<void(const std::vector<Segment>&)> prepare{};
    bool perPath = false; ///< time per path, not per evaluation (a build cost)
};

double percentile(std::vector<double> v, double q)
{
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const double pos = q * double(v.size() - 1);
    const auto i = std::size_t(pos);
    const double f = pos - double(i);
    return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
}

std::string fraction(double f) { return f == 1.0 ? "1" : "1/" + std::to_string(int(std::lround(1.0 / f))); }

} // namespace

std::string machineDescription()
{
    std::ifstream in("/proc/cpuinfo");
    std::string line, model = "unknown CPU";
    while (std::getline(in, line)) {
        if (line.rfind("model name", 0) == 0) {
            model = line.substr(line.find(':') + 2);
            break;
        }
    }
    return model + " (" + std::to_string(std::thread::hardware_concurrency()) + " cores)";
}

namespace {

/// The workload @p name, with the reference of its voxel reading.
Workload buildWorkload(
    const std::string& name, const SamplerBenchOptions& o, std::mt19937& rng, const Progress& progress)
{
    progress(-1.0, "building the " + name + " workload");
    Workload w;
    if (name == "slab") {
        w = slabWorkload(o, rng);
    } else if (name == "torso") {
        w = torsoWorkload(o, rng);
    } else if (name == "ct" || name == "mr") {
        w = name == "ct" ? ctWorkload(o, rng, progress) : mrWorkload(o, rng, progress);
        exactVoxelReference(w);
    } else {
        throw ValueError("bench sampler: unknown workload '" + name + "' (slab, torso, ct, mr)");
    }
    return w;
}

/// Per path, per shaft: the exact value of one reading.
using PathValues = std::vector<std::vector<double>>;

/// References per shaft of @p paths: the voxel reading (@p pcReference) and
/// the trilinear reading (@p tri).
void shaftReferences(const std::vector<std::vector<Segment>>& paths,
    const std::function<double(const Segment&)>& pcReference, haptic::ShaftIntegrator& tri, PathValues& refPc,
    PathValues& refTri)
{
    for (const auto& path : paths) {
        std::vector<double> pc, tr;
        for (const auto& s : path) {
            ShaftIntegral r;
            tri.integrate(s, r);
            pc.push_back(pcReference(s));
            tr.push_back(r.dampingIntegral);
        }
        refPc.push_back(std::move(pc));
        refTri.push_back(std::move(tr));
    }
}

/// The march steps timed, as fractions of a voxel.
constexpr double kStepFractions[] = {1.0, 0.5, 0.25, 0.1};

/// The integrators' configurations, built once; labels off: the damping force
/// only. Each keeps one result struct, as the servo does (NeedleForceModel's):
/// a fresh one per batch zeroes 1 KiB of label arrays, which is not the
/// strategy's cost.
void addIntegratorConfigs(std::vector<Config>& configs, const haptic::MaterialField& field, double h)
{
    const auto add = [&](std::string label, std::string reading, haptic::IntegratorOptions io) {
        io.trackLabels = false;
        std::shared_ptr<haptic::ShaftIntegrator> integ = haptic::makeIntegrator(field, io);
        configs.push_back({std::move(label), std::move(reading),
            [integ, r = std::make_shared<ShaftIntegral>()](const std::vector<Segment>& path, std::vector<double>& out) {
                for (std::size_t i = 0; i < path.size(); ++i) {
                    integ->integrate(path[i], *r);
                    out[i] = r->dampingIntegral;
                }
            }});
    };
    add("exact-voxel", "voxel", {haptic::Strategy::ExactVoxel});
    add("exact-trilinear", "trilinear", {haptic::Strategy::ExactTrilinear});
    auto peer = std::make_shared<BlockDdaPeer>(field);
    configs.push_back(
        {"peer: vdb block DDA", "voxel", [peer](const std::vector<Segment>& path, std::vector<double>& out) {
             for (std::size_t i = 0; i < path.size(); ++i) out[i] = peer->integrate(path[i]);
         }});
    for (double f : kStepFractions) {
        add("vdb march-nearest " + fraction(f), "voxel", {haptic::Strategy::MarchNearest, f * h});
        add("vdb march-trilinear " + fraction(f), "trilinear", {haptic::Strategy::MarchTrilinear, f * h});
    }
}

/// The profile: locked to each path's line before its batch is timed (the
/// servo locks once after skin puncture); the lock itself is a row of its own.
void addProfileConfigs(std::vector<Config>& configs, const haptic::MaterialField& field)
{
    for (double tol : {0.01, 0.05}) {
        auto profile = std::make_shared<haptic::TrajectoryProfile>(field, tol, 110.0, false);
        std::ostringstream label;
        label << "profile tol " << tol << " mm";
        configs.push_back({label.str(), "voxel",
            [profile, r = std::make_shared<ShaftIntegral>()](
                const std::vector<Segment>& path, std::vector<double>& out) {
                for (std::size_t i = 0; i < path.size(); ++i) {
                    profile->integrate(path[i], *r);
                    out[i] = r->dampingIntegral;
                }
            },
            [profile](const std::vector<Segment>& path) {
                profile->lock(path.front().entry, path.front().tip - path.front().entry);
            }});
    }
    auto profile = std::make_shared<haptic::TrajectoryProfile>(field, 0.05, 110.0, false);
    configs.push_back({"profile lock (per path)", "build",
        [profile](const std::vector<Segment>& path, std::vector<double>& out) {
            profile->lock(path.front().entry, path.front().tip - path.front().entry);
            std::fill(out.begin(), out.end(), std::nan(""));
        },
        {}, true});
}

/// The textbook baselines on a dense copy of the field: its marches, and VTK's
/// probe filter when asked for.
void addDenseConfigs(std::vector<Config>& configs, const haptic::MaterialField& field, double h,
    const SamplerBenchOptions& o, const std::string& name, const Progress& progress)
{
    progress(-1.0, "copying the " + name + " workload to a dense array");
    auto dense = std::make_shared<DenseField>(field);
    for (double f : kStepFractions) {
        for (bool trilinear : {false, true}) {
            configs.push_back({std::string("dense march-") + (trilinear ? "trilinear " : "nearest ") + fraction(f),
                trilinear ? "trilinear" : "voxel",
                [dense, f, h, trilinear](const std::vector<Segment>& path, std::vector<double>& out) {
                    for (std::size_t i = 0; i < path.size(); ++i) out[i] = dense->march(path[i], f * h, trilinear);
                }});
        }
    }
    if (!o.vtk) return;
    auto probe = std::make_shared<VtkProbe>(*dense);
    for (double f : {1.0, 0.25}) {
        configs.push_back({"vtkProbeFilter " + fraction(f), "trilinear",
            [probe, f, h](const std::vector<Segment>& path, std::vector<double>& out) {
                for (std::size_t i = 0; i < path.size(); ++i) out[i] = probe->integrate(path[i], f * h);
            }});
    }
}

/// What the interleaved rounds measured, per configuration.
struct Timings {
    std::vector<std::vector<double>> batchNs; ///< per batch (path) of every round [ns per evaluation]
    std::vector<std::vector<double>> values;  ///< of the first round, path after path
};

/// Interleaved rounds: every configuration, every path, then again.
Timings timeInterleaved(const std::vector<Config>& configs, const Workload& w, const SamplerBenchOptions& o,
    std::mt19937& rng, const Progress& progress)
{
    Timings t;
    t.batchNs.resize(configs.size());
    t.values.resize(configs.size());
    std::vector<double> out(std::size_t(o.depths));
    // Path by path, every configuration in a fresh random order: each one
    // meets the caches as the others left them as often as any other does
    // (a fixed order favours whoever follows a configuration that walked
    // the same grid, and penalises whoever follows a dense march).
    std::vector<std::vector<double>> valueByPath(configs.size() * w.paths.size());
    std::vector<std::size_t> order(configs.size());
    for (std::size_t c = 0; c < order.size(); ++c) order[c] = c;
    for (int rep = 0; rep < o.repetitions; ++rep) {
        progress(-1.0, w.name + ": round " + std::to_string(rep + 1) + " of " + std::to_string(o.repetitions));
        for (std::size_t p = 0; p < w.paths.size(); ++p) {
            std::shuffle(order.begin(), order.end(), rng);
            for (const std::size_t c : order) {
                if (configs[c].prepare) configs[c].prepare(w.paths[p]);
                const auto t0 = Clock::now();
                configs[c].run(w.paths[p], out);
                const auto t1 = Clock::now();
                const double per = configs[c].perPath ? 1.0 : double(out.size());
                t.batchNs[c].push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() / per);
                if (rep == 0) valueByPath[c * w.paths.size() + p] = out;
            }
        }
    }
    for (std::size_t c = 0; c < configs.size(); ++c) {
        for (std::size_t p = 0; p < w.paths.size(); ++p) {
            const auto& v = valueByPath[c * w.paths.size() + p];
            t.values[c].insert(t.values[c].end(), v.begin(), v.end());
        }
    }
    return t;
}

/// One row per configuration: its times, and its force errors at @p v0
/// against both references.
void addRows(SamplerReport& report, const Workload& w, const std::vector<Config>& configs, const Timings& t,
    const PathValues& refPc, const PathValues& refTri, double v0)
{
    for (std::size_t c = 0; c < configs.size(); ++c) {
        SamplerRow row;
        row.workload = w.name;
        row.config = configs[c].name;
        row.reading = configs[c].reading;
        row.nsMedian = percentile(t.batchNs[c], 0.5);
        row.nsP99 = percentile(t.batchNs[c], 0.99);
        if (configs[c].perPath) { // a build cost: no error to report
            row.evaluations = long(w.paths.size());
            report.rows.push_back(row);
            continue;
        }
        double sumPc = 0, sumTri = 0;
        std::size_t k = 0;
        for (std::size_t p = 0; p < w.paths.size(); ++p) {
            for (std::size_t i = 0; i < w.paths[p].size(); ++i, ++k) {
                const double ePc = v0 * std::abs(t.values[c][k] - refPc[p][i]);
                const double eTri = v0 * std::abs(t.values[c][k] - refTri[p][i]);
                row.errMaxN = std::max(row.errMaxN, ePc);
                row.errTriMaxN = std::max(row.errTriMaxN, eTri);
                sumPc += ePc * ePc;
                sumTri += eTri * eTri;
            }
        }
        row.evaluations = long(k);
        row.errRmsN = std::sqrt(sumPc / double(std::max<std::size_t>(k, 1)));
        row.errTriRmsN = std::sqrt(sumTri / double(std::max<std::size_t>(k, 1)));
        report.rows.push_back(row);
    }
}

/// The row of @p config on @p workload (the first row if there is none).
const SamplerRow& findRow(const SamplerReport& report, const std::string& workload, const std::string& config)
{
    for (const auto& r : report.rows) {
        if (r.workload == workload && r.config == config) return r;
    }
    return report.rows.front();
}

/// The textbook baseline: the dense trilinear march at 1/4 voxel.
const char* const kBaseline = "dense march-trilinear 1/4";

/// How many times faster than the baseline @p config ran (median times).
double overBaseline(const SamplerReport& report, const std::string& workload, const std::string& config)
{
    return findRow(report, workload, kBaseline).nsMedian / findRow(report, workload, config).nsMedian;
}

/// The values of configuration @p config (the first one's if there is none).
const std::vector<double>& valuesOf(const std::vector<Config>& configs, const Timings& t, const std::string& config)
{
    for (std::size_t c = 0; c < configs.size(); ++c) {
        if (configs[c].name == config) return t.values[c];
    }
    return t.values[0];
}

/// The locked profile's largest deviation from exact-voxel on the timed
/// paths, as a force at @p v0 [N].
double profileDeviation(const std::vector<Config>& configs, const Timings& t, double v0)
{
    double dev = 0;
    const auto& prof = valuesOf(configs, t, "profile tol 0.05 mm");
    const auto& exactValues = valuesOf(configs, t, "exact-voxel");
    for (std::size_t k = 0; k < prof.size(); ++k) dev = std::max(dev, v0 * std::abs(prof[k] - exactValues[k]));
    return dev;
}

/// Ratios in this run against the textbook baseline (dense trilinear march at
/// 1/4 voxel). @p deviation: the profile's largest deviation from exact-voxel [N].
void addSpeedNotes(SamplerReport& report, const Workload& w, double deviation)
{
    const std::string& name = w.name;
    const SamplerRow& base = findRow(report, name, kBaseline);
    const auto ratio = [&](const std::string& config) { return overBaseline(report, name, config); };
    std::ostringstream n;
    n << std::fixed << std::setprecision(1);
    n << name << ": exact-voxel is " << ratio("exact-voxel") << "x faster than the dense trilinear march at 1/4 voxel"
      << " (target >= 10x), max error " << std::setprecision(3) << std::scientific
      << findRow(report, name, "exact-voxel").errMaxN << " N vs " << base.errMaxN << " N (" << w.pcReferenceName << ")";
    report.notes.push_back(n.str());
    n.str("");
    n << std::fixed << std::setprecision(1) << name << ": exact-trilinear is " << ratio("exact-trilinear")
      << "x faster than that march; error against the trilinear reading " << std::scientific << std::setprecision(3)
      << findRow(report, name, "exact-trilinear").errTriMaxN << " N vs " << base.errTriMaxN << " N";
    report.notes.push_back(n.str());
    n.str("");
    n << std::fixed << std::setprecision(1) << name << ": profile (tol 0.05 mm) is " << ratio("profile tol 0.05 mm")
      << "x faster than that march (target >= 300x); max deviation from exact-voxel on the locked paths "
      << std::scientific << std::setprecision(3);
    n << deviation << " N (target <= 1e-6 N)";
    report.notes.push_back(n.str());
}

/// The peer: same grid, same segments; exact-voxel must take <= 0.8x its time
/// and agree to 1e-12 relative (the sums differ only by round-off in the chords).
/// Both are also held against the plane-crossing sum in long double of the same
/// index-space segment (no walk): where the two differ, it says which one is
/// off. Relative differences are largest on shafts that cross a sliver of tissue
/// (a sum far below β_max·length, while each crossing time carries round-off of
/// the index coordinates), so they are also given relative to β_max·length.
WorkloadSummary peerSummary(
    const SamplerReport& report, const Workload& w, const std::vector<Config>& configs, const Timings& t)
{
    const PlaneCrossingSum planes(*w.field);
    const auto& peerValues = valuesOf(configs, t, "peer: vdb block DDA");
    const auto& exactValues = valuesOf(configs, t, "exact-voxel");
    WorkloadSummary sum;
    sum.workload = w.name;
    std::size_t k2 = 0;
    for (const auto& path : w.paths) {
        for (const auto& seg : path) {
            const double ref = planes.integrate(seg), bound = planes.largestValue() * (seg.tip - seg.entry).norm();
            const auto rel = [](double x, double y) {
                return x == y ? 0.0 : std::abs(x - y) / std::max(std::abs(y), 1e-300);
            };
            sum.sumsRelativeDifference = std::max(sum.sumsRelativeDifference, rel(peerValues[k2], exactValues[k2]));
            sum.exactRelativeError = std::max(sum.exactRelativeError, rel(exactValues[k2], ref));
            sum.peerRelativeError = std::max(sum.peerRelativeError, rel(peerValues[k2], ref));
            if (bound > 0.0) {
                sum.exactScaledError = std::max(sum.exactScaledError, std::abs(exactValues[k2] - ref) / bound);
                sum.peerScaledError = std::max(sum.peerScaledError, std::abs(peerValues[k2] - ref) / bound);
            }
            ++k2;
        }
    }
    sum.exactOverPeer =
        findRow(report, w.name, "exact-voxel").nsMedian / findRow(report, w.name, "peer: vdb block DDA").nsMedian;
    sum.marchOverExact = overBaseline(report, w.name, "exact-voxel");
    sum.marchOverProfile = overBaseline(report, w.name, "profile tol 0.05 mm");
    return sum;
}

/// The note of the peer summary @p sum.
std::string peerNote(const WorkloadSummary& sum)
{
    std::ostringstream n;
    n << std::fixed << std::setprecision(2) << sum.workload << ": exact-voxel takes " << sum.exactOverPeer
      << "x the time of the two-level OpenVDB block DDA peer (target <= 0.8x); largest relative difference of "
         "their sums "
      << std::scientific << std::setprecision(2) << sum.sumsRelativeDifference
      << " (target <= 1e-12); against the plane-crossing sum in long double, exact-voxel " << sum.exactRelativeError
      << ", peer " << sum.peerRelativeError << " relative (" << sum.exactScaledError << " and " << sum.peerScaledError
      << " of beta_max x length)";
    return n.str();
}

/// RMS, 99th percentile and maximum of @p e.
void errorStats(const std::vector<double>& e, double& rms, double& p99, double& max)
{
    double sq = 0;
    for (double x : e) sq += x * x;
    rms = std::sqrt(sq / double(std::max<std::size_t>(e.size(), 1)));
    p99 = percentile(e, 0.99);
    max = e.empty() ? 0.0 : *std::max_element(e.begin(), e.end());
}

/// Path-based fidelity (in the manner of Mastmeyer et al. 2017): many more
/// random paths, untimed, each strategy against the exact reference of its
/// reading and against the exact trilinear reading.
void addFidelityRows(SamplerReport& report, const Workload& w, const std::vector<Config>& configs,
    haptic::ShaftIntegrator& tri, const SamplerBenchOptions& o, const Progress& progress)
{
    if (o.fidelityPaths <= 0 || !w.morePaths) return;
    const double v0 = o.speedMmPerS;
    progress(-1.0, w.name + ": fidelity on " + std::to_string(o.fidelityPaths) + " paths");
    std::mt19937 fidelityRng(20261125);
    const auto fpaths = w.morePaths(o.fidelityPaths, o.fidelityDepths, fidelityRng);
    PathValues refVoxel, refTrilinear;
    shaftReferences(fpaths, w.pcReference, tri, refVoxel, refTrilinear);
    std::vector<double> got(std::size_t(o.fidelityDepths));
    for (const Config& cfg : configs) {
        if (cfg.perPath || cfg.name.rfind("dense", 0) == 0 || cfg.name.rfind("vtk", 0) == 0) continue;
        std::vector<double> own, vsTri;
        for (std::size_t p = 0; p < fpaths.size(); ++p) {
            if (cfg.prepare) cfg.prepare(fpaths[p]);
            got.resize(fpaths[p].size());
            cfg.run(fpaths[p], got);
            for (std::size_t i = 0; i < got.size(); ++i) {
                const double ref = cfg.reading == "trilinear" ? refTrilinear[p][i] : refVoxel[p][i];
                own.push_back(v0 * std::abs(got[i] - ref));
                vsTri.push_back(v0 * std::abs(got[i] - refTrilinear[p][i]));
            }
        }
        FidelityRow f;
        f.workload = w.name;
        f.config = cfg.name;
        f.reading = cfg.reading;
        f.paths = long(fpaths.size());
        f.evaluations = long(own.size());
        f.nsMedian = findRow(report, w.name, cfg.name).nsMedian;
        errorStats(own, f.rmsN, f.p99N, f.maxN);
        errorStats(vsTri, f.triRmsN, f.triP99N, f.triMaxN);
        report.fidelity.push_back(f);
    }
}

} // namespace

SamplerReport runSamplerBench(const SamplerBenchOptions& o, const Progress& progress)
{
    SamplerReport report;
    report.machine = machineDescription();
    report.options = o;
    std::mt19937 rng(20261122);
    for (const std::string& name : o.workloads) {
        const Workload w = buildWorkload(name, o, rng, progress);
        const double h = w.voxelMm, v0 = o.speedMmPerS;
        const haptic::MaterialField& field = *w.field;
        PathValues refPc, refTri;
        auto tri = haptic::makeIntegrator(field, {haptic::Strategy::ExactTrilinear, 0.1, false});
        shaftReferences(w.paths, w.pcReference, *tri, refPc, refTri);

        std::vector<Config> configs;
        addIntegratorConfigs(configs, field, h);
        addProfileConfigs(configs, field);
        addDenseConfigs(configs, field, h, o, name, progress);
        const Timings timings = timeInterleaved(configs, w, o, rng, progress);
        addRows(report, w, configs, timings, refPc, refTri, v0);

        const double deviation = profileDeviation(configs, timings, v0);
        addSpeedNotes(report, w, deviation);
        WorkloadSummary sum = peerSummary(report, w, configs, timings);
        sum.profileDeviationN = deviation;
        report.summary.push_back(sum);
        report.notes.push_back(peerNote(sum));
        addFidelityRows(report, w, configs, *tri, o, progress);
    }
    return report;
}

void printSamplerReport(std::ostream& os, const SamplerReport& r)
{
    os << "shaft integration: runtime versus error\n";
    os << "machine: " << r.machine << "\n";
    os << "workload: " << r.options.paths << " paths x " << r.options.depths << " depths (to 100 mm, tilt 0-60 deg), "
       << r.options.repetitions << " interleaved rounds; voxel " << r.options.spacingMm << " mm; errors at "
       << r.options.speedMmPerS << " mm/s\n";
    os << "ns per evaluation: median and p99 over per-path batches of " << r.options.depths << " evaluations\n\n";
    std::string current;
    for (const auto& row : r.rows) {
        if (row.workload != current) {
            current = row.workload;
            os << "[" << current << "]\n";
            os << std::left << std::setw(28) << "configuration" << std::right << std::setw(10) << "median ns"
               << std::setw(11) << "p99 ns" << std::setw(13) << "max err N" << std::setw(13) << "rms err N"
               << std::setw(14) << "max err(tri)" << std::setw(14) << "rms err(tri)" << '\n';
        }
        os << std::left << std::setw(28) << row.config << std::right << std::fixed << std::setprecision(0)
           << std::setw(10) << row.nsMedian << std::setw(11) << row.nsP99 << std::scientific << std::setprecision(2)
           << std::setw(13) << row.errMaxN << std::setw(13) << row.errRmsN << std::setw(14) << row.errTriMaxN
           << std::setw(14) << row.errTriRmsN << '\n';
    }
    os << std::defaultfloat << '\n';
    for (const auto& n : r.notes) os << "- " << n << '\n';
    if (!r.fidelity.empty()) {
        os << "\npath-based fidelity: force error at " << r.options.speedMmPerS << " mm/s over "
           << r.options.fidelityPaths << " random paths x " << r.options.fidelityDepths
           << " depths per workload, against the exact reference of each reading and against exact trilinear\n";
        std::string currentWorkload;
        for (const auto& f : r.fidelity) {
            if (f.workload != currentWorkload) {
                currentWorkload = f.workload;
                os << "[" << currentWorkload << "]\n";
                os << std::left << std::setw(28) << "configuration" << std::right << std::setw(10) << "median ns"
                   << std::setw(12) << "rms N" << std::setw(12) << "p99 N" << std::setw(12) << "max N" << std::setw(14)
                   << "rms N (tri)" << std::setw(14) << "p99 N (tri)" << std::setw(14) << "max N (tri)" << '\n';
            }
            os << std::left << std::setw(28) << f.config << std::right << std::fixed << std::setprecision(0)
               << std::setw(10) << f.nsMedian << std::scientific << std::setprecision(2) << std::setw(12) << f.rmsN
               << std::setw(12) << f.p99N << std::setw(12) << f.maxN << std::setw(14) << f.triRmsN << std::setw(14)
               << f.triP99N << std::setw(14) << f.triMaxN << '\n';
        }
        os << std::defaultfloat;
    }
}

nlohmann::json samplerReportJson(const SamplerReport& r)
{
    nlohmann::json j;
    j["machine"] = r.machine;
    j["options"] = {{"workloads", r.options.workloads}, {"paths", r.options.paths}, {"depths", r.options.depths},
        {"repetitions", r.options.repetitions}, {"speed_mm_per_s", r.options.speedMmPerS},
        {"spacing_mm", r.options.spacingMm}, {"fidelity_paths", r.options.fidelityPaths},
        {"fidelity_depths", r.options.fidelityDepths}};
    nlohmann::json rows = nlohmann::json::array();
    const std::vector<bool> front = paretoFront(r.rows);
    for (std::size_t i = 0; i < r.rows.size(); ++i) {
        const SamplerRow& row = r.rows[i];
        rows.push_back({{"workload", row.workload}, {"config", row.config}, {"family", strategyFamily(row.config)},
            {"pareto", bool(front[i])}, {"reading", row.reading}, {"ns_median", row.nsMedian}, {"ns_p99", row.nsP99},
            {"err_max_n", row.errMaxN}, {"err_rms_n", row.errRmsN}, {"err_trilinear_max_n", row.errTriMaxN},
            {"err_trilinear_rms_n", row.errTriRmsN}, {"evaluations", row.evaluations}});
    }
    j["rows"] = rows;
    nlohmann::json fidelity = nlohmann::json::array();
    for (const auto& f : r.fidelity) {
        fidelity.push_back({{"workload", f.workload}, {"config", f.config}, {"reading", f.reading}, {"paths", f.paths},
            {"evaluations", f.evaluations}, {"ns_median", f.nsMedian}, {"err_rms_n", f.rmsN}, {"err_p99_n", f.p99N},
            {"err_max_n", f.maxN}, {"err_trilinear_rms_n", f.triRmsN}, {"err_trilinear_p99_n", f.triP99N},
            {"err_trilinear_max_n", f.triMaxN}});
    }
    j["fidelity"] = fidelity;
    nlohmann::json summary = nlohmann::json::array();
    for (const auto& w : r.summary) {
        summary.push_back({{"workload", w.workload}, {"march_over_exact_voxel", w.marchOverExact},
            {"march_over_profile", w.marchOverProfile}, {"exact_voxel_over_peer", w.exactOverPeer},
            {"profile_deviation_n", w.profileDeviationN}, {"sums_relative_difference", w.sumsRelativeDifference},
            {"exact_voxel_relative_error", w.exactRelativeError}, {"peer_relative_error", w.peerRelativeError},
            {"exact_voxel_error_of_bound", w.exactScaledError}, {"peer_error_of_bound", w.peerScaledError}});
    }
    j["summary"] = summary;
    j["notes"] = r.notes;
    return j;
}

std::string strategyFamily(const std::string& config)
{
    for (const char* f : {"exact", "peer", "profile", "vdb march-nearest", "vdb march-trilinear", "dense march-nearest",
             "dense march-trilinear", "vtkProbeFilter"}) {
        if (config.rfind(f, 0) == 0) return f;
    }
    return config;
}

namespace {

/// The error each row is judged by on the front: against the finest reading,
/// the exact trilinear one. Against its own reading every exact strategy and
/// the locked profile are exact (0), and the front would be one point.
double rowError(const SamplerRow& row) { return row.errTriMaxN; }

} // namespace

std::vector<bool> paretoFront(const std::vector<SamplerRow>& rows)
{
    // A row is on the front when no other row of its workload is at least as good
    // on both time and error and better on one (build rows are not evaluations).
    std::vector<bool> front(rows.size(), false);
    for (std::size_t i = 0; i < rows.size(); ++i) {
        if (rows[i].reading == "build") continue;
        bool dominated = false;
        for (std::size_t j = 0; j < rows.size() && !dominated; ++j) {
            if (j == i || rows[j].workload != rows[i].workload || rows[j].reading == "build") continue;
            const double ti = rows[i].nsMedian, tj = rows[j].nsMedian, ei = rowError(rows[i]), ej = rowError(rows[j]);
            // Errors that differ by round-off only (the exact strategies of one
            // reading, 1e-14 N apart) count as equal, or each would keep the other on.
            const double same = 1e-9 * std::max(ei, ej) + 1e-15;
            const bool noWorse = ej <= ei + same, better = ej < ei - same;
            dominated = tj <= ti && noWorse && (tj < ti || better);
        }
        front[i] = !dominated;
    }
    return front;
}

bool plotSamplerReport(const SamplerReport& r, const std::string& pngFile, std::string& why)
{
    const render::PlotDir dir;
    const std::vector<bool> front = paretoFront(r.rows);
    std::vector<std::string> workloads, families;
    for (const auto& row : r.rows) {
        if (row.reading == "build") continue;
        if (std::find(workloads.begin(), workloads.end(), row.workload) == workloads.end())
            workloads.push_back(row.workload);
        const std::string f = strategyFamily(row.config);
        if (std::find(families.begin(), families.end(), f) == families.end()) families.push_back(f);
    }
    // One data file per workload and family, one per workload for its front (sorted by error).
    const auto file = [&](const std::string& w, std::size_t f) {
        return (dir.path() / (w + "-" + std::to_string(f) + ".dat")).string();
    };
    for (const auto& w : workloads) {
        std::vector<std::pair<double, double>> frontPoints;
        for (std::size_t f = 0; f < families.size(); ++f) {
            std::ofstream data(file(w, f));
            for (std::size_t i = 0; i < r.rows.size(); ++i) {
                const SamplerRow& row = r.rows[i];
                if (row.workload != w || row.reading == "build" || strategyFamily(row.config) != families[f]) continue;
                data << std::max(rowError(row), 1e-12) << ' ' << row.nsMedian << '\n';
            }
        }
        for (std::size_t i = 0; i < r.rows.size(); ++i) {
            if (r.rows[i].workload == w && front[i])
                frontPoints.emplace_back(std::max(rowError(r.rows[i]), 1e-12), r.rows[i].nsMedian);
        }
        std::sort(frontPoints.begin(), frontPoints.end());
        std::ofstream data(dir.path() / (w + "-front.dat"));
        for (const auto& [e, t] : frontPoints) data << e << ' ' << t << '\n';
    }
    const int columns = workloads.size() > 1 ? 2 : 1;
    const int rowsN = int((workloads.size() + std::size_t(columns) - 1) / std::size_t(columns));
    std::ostringstream script;
    script << "set multiplot layout " << rowsN << "," << columns << " title 'shaft integration, runtime versus error ("
           << r.machine << ")'\n"
           << "set logscale xy\nset grid\nset key top center font ',8' maxrows 3\n"
           << "set xlabel 'max force error at " << r.options.speedMmPerS
           << " mm/s against the exact trilinear reading [N] (0 drawn at 1e-12)'\n"
           << "set ylabel 'median ns per evaluation'\n";
    for (const auto& w : workloads) {
        script << "set title '" << w << "'\nplot ";
        for (std::size_t f = 0; f < families.size(); ++f) {
            script << "'" << file(w, f) << "' using 1:2 with points pt 7 ps 1.2 lc " << f + 1 << " title '"
                   << families[f] << "', ";
        }
        script << "'" << (dir.path() / (w + "-front.dat")).string()
               << "' using 1:2 with steps lw 2 lc rgb 'black' title 'Pareto front'\n";
    }
    script << "unset multiplot\n";
    return render::runGnuplot(dir, script.str(), pngFile, 1400, 500 * rowsN, why);
}

} // namespace voxhap::bench
