// SPDX-License-Identifier: Apache-2.0
/// @file bench_fusion.cpp
/// @brief CT–MR registration and fusion against Debian's elastix, interleaved
/// in one run (docs/benchmarks.md: comparisons as ratios from one run):
///
/// - the shared porcine pair (a feet-first CT, a head-first T2 MR): voxhap's
///   whole rigid registration (orientation search included, reported apart)
///   against elastix's process with 2 threads on raw NRRD, with the parameter
///   file and start the agreement test pins (tests/registration/elastix/);
///   then the fusion after it (resampling onto the CT's grid, the labels from
///   both scans) and the process's peak memory against dense float copies of
///   the CT;
/// - the lumbar and torso phantoms' CT with an MR moved by a known rigid map:
///   voxhap from its own search, elastix from voxhap's post-search start, both
///   timed in interleaved repeats (the ratio is voxhap's time after its search
///   over elastix's), and both held to the truth over the body (target
///   registration error, mean and max).
///
///     bench_fusion [--repeats N] [--json] [--elastix PROGRAM]
///
/// The pyramid is voxhap's default (RegistrationOptions: 3 levels, finest
/// 1.2 mm); elastix's is its own (3 levels of its recursive pyramid, full
/// resolution last), as the pinned parameter file says.

#include "bench/ProcessFigures.h"
#include "bench/Stats.h"
#include "phantoms/PhantomScans.h"
#include "registration/Fusion.h"
#include "registration/Registration.h"
#include "registration/Resample.h"
#include "segmentation/FusedLabels.h"
#include "volume/Grids.h"
#include "volume/VolumeFile.h"
#include "volume/io/NrrdFile.h"

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace {

using namespace voxhap;
using bench::loadAverage;
using bench::peakRssMb;
using bench::rssMb;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

fs::path elastixDir() { return fs::path(VOXHAP_SOURCE_DIR) / "tests" / "registration" / "elastix"; }

/// elastix's answer as a map CT point → MR point: its Euler transform (R =
/// Rz·Rx·Ry about its centre, ComputeZYX false) after the initial transform it
/// was given (HowToCombineTransforms Compose).
registration::AffineMap readElastixAnswer(const fs::path& file, const registration::AffineMap& initial)
{
    std::ifstream in(file);
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string text = ss.str();
    const auto numbers = [&text, &file](const std::string& key) {
        std::smatch m;
        if (!std::regex_search(text, m, std::regex("\\(" + key + " ([^)]*)\\)")))
            throw std::runtime_error(file.string() + ": no " + key);
        std::istringstream v(m[1].str());
        std::vector<double> out;
        double x;
        while (v >> x) out.push_back(x);
        return out;
    };
    const std::vector<double> p = numbers("TransformParameters");
    const std::vector<double> c = numbers("CenterOfRotationPoint");
    if (p.size() != 6 || c.size() != 3) throw std::runtime_error(file.string() + ": not a 3D Euler transform");
    const Mat3d r = (Eigen::AngleAxisd(p[2], Vec3d::UnitZ()) * Eigen::AngleAxisd(p[0], Vec3d::UnitX()) *
        Eigen::AngleAxisd(p[1], Vec3d::UnitY()))
                        .toRotationMatrix();
    const Vec3d centre(c[0], c[1], c[2]);
    const registration::AffineMap euler{r, centre - r * centre + Vec3d(p[3], p[4], p[5])};
    return {euler.linear * initial.linear, euler.linear * initial.offset + euler.offset};
}

/// An elastix initial transform file holding @p map (CT point → MR point).
void writeElastixInitial(const registration::AffineMap& map, const fs::path& file)
{
    std::ofstream out(file);
    out.precision(17);
    out << "(Transform \"AffineTransform\")\n(NumberOfParameters 12)\n(TransformParameters";
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) out << ' ' << map.linear(r, c);
    out << ' ' << map.offset.x() << ' ' << map.offset.y() << ' ' << map.offset.z() << ")\n";
    out << "(CenterOfRotationPoint 0 0 0)\n(InitialTransformParametersFileName \"NoInitialTransform\")\n"
           "(HowToCombineTransforms \"Compose\")\n(FixedImageDimension 3)\n(MovingImageDimension 3)\n"
           "(FixedInternalImagePixelType \"float\")\n(MovingInternalImagePixelType \"float\")\n"
           "(UseDirectionCosines \"true\")\n";
}

struct ElastixRun {
    double seconds = 0;
    fs::path parameters; ///< TransformParameters.0.txt
};

ElastixRun runElastix(
    const std::string& program, const fs::path& ct, const fs::path& mr, const fs::path& initial, const fs::path& out)
{
    fs::remove_all(out);
    fs::create_directories(out);
    const std::string cmd = program + " -f '" + ct.string() + "' -m '" + mr.string() + "' -p '" +
        (elastixDir() / "rigid-mattes.txt").string() + "' -t0 '" + initial.string() + "' -out '" + out.string() +
        "' -threads 2 > '" + (out / "stdout.txt").string() + "' 2>&1";
    const auto t0 = Clock::now();
    if (std::system(cmd.c_str()) != 0) throw std::runtime_error("elastix failed: " + cmd);
    return {seconds(t0), out / "TransformParameters.0.txt"};
}

/// Mean and max distance between two maps over @p points.
std::pair<double, double> distance(
    const registration::AffineMap& a, const registration::AffineMap& b, const std::vector<Vec3d>& points)
{
    double sum = 0, worst = 0;
    for (const Vec3d& p : points) {
        const double d = (a.apply(p) - b.apply(p)).norm();
        sum += d;
        worst = std::max(worst, d);
    }
    return {points.empty() ? 0.0 : sum / double(points.size()), worst};
}

/// Every @p stride-th CT voxel with HU above −500: the body the maps are compared over.
std::vector<Vec3d> bodyPoints(const volume::Volume& ct, int stride)
{
    std::vector<Vec3d> points;
    const auto acc = volume::huGrid(ct)->getConstAccessor();
    const auto& b = ct.indexBox();
    for (int k = b.min.z(); k <= b.max.z(); k += stride)
        for (int j = b.min.y(); j <= b.max.y(); j += stride)
            for (int i = b.min.x(); i <= b.max.x(); i += stride)
                if (acc.getValue(openvdb::Coord(i, j, k)) > -500.0f) points.push_back(ct.indexToWorld(Vec3d(i, j, k)));
    return points;
}

nlohmann::json stats(const std::vector<double>& x)
{
    const bench::SampleStats s = bench::sampleStats(x);
    return {{"median", s.median}, {"mean", s.mean}, {"sd", s.sd}, {"n", s.n}};
}

nlohmann::json porcine(const std::string& elastix, int repeats, const fs::path& work)
{
    const fs::path dir = fs::path(VOXHAP_SOURCE_DIR) / ".." / "shared" / "data" / "ct-mr-porcine";
    nlohmann::json out;
    if (!fs::is_directory(dir / "ct") || !fs::is_directory(dir / "mr-t2")) {
        out["skipped"] = "no shared porcine pair at " + dir.string();
        return out;
    }
    const volume::Volume ct = volume::loadVolume(dir / "ct");
    const volume::Volume mr = volume::loadVolume(dir / "mr-t2");
    // The targets are measured above the loaded volumes (registration,
    // resampling and the fused grids); the loader's own peak is behind us.
    const double loadedMb = rssMb();
    volume::saveNrrd(ct, volume::Channel::Hu, work / "ct.nrrd", volume::NrrdEncoding::Raw);
    volume::saveNrrd(mr, volume::Channel::Intensity, work / "mr.nrrd", volume::NrrdEncoding::Raw);
    const std::vector<Vec3d> points = bodyPoints(ct, 4);

    std::vector<double> ours, search, theirs, ratio, agreement;
    registration::RegistrationResult last;
    for (int r = 0; r < repeats; ++r) {
        // Interleaved: each repeat times both, so that load from other processes falls on both.
        last = registration::registerMrToCt(ct, mr);
        ours.push_back(last.seconds);
        search.push_back(last.searchSeconds);
        const ElastixRun e =
            runElastix(elastix, work / "ct.nrrd", work / "mr.nrrd", elastixDir() / "porcine-initial.txt", work / "el");
        theirs.push_back(e.seconds);
        ratio.push_back(last.seconds / e.seconds);
        // elastix's start: 180° about y through the CT's centre (porcine-initial.txt).
        const Vec3d c(-0.1953125, -0.1953125, 5.25);
        const Mat3d turn = Eigen::AngleAxisd(3.14159265358979323846, Vec3d::UnitY()).toRotationMatrix();
        agreement.push_back(
            distance(last.mrFromCt, readElastixAnswer(e.parameters, {turn, c - turn * c}), points).first);
    }
    // The fusion after the registration: the MR resampled onto the CT's grid
    // and the fused volume's grids (hu shared). The labels from both scans are
    // segmentation, which keeps its own targets (bench_segment); timed apart.
    const auto t0 = Clock::now();
    registration::ResampleReport rr;
    volume::Volume fused(ct.geometry(), ct.indexBox());
    fused.setGrid(volume::Channel::Hu, std::const_pointer_cast<openvdb::GridBase>(ct.grid(volume::Channel::Hu)));
    const volume::Channel moving = registration::movingChannel(mr);
    fused.setGrid(moving, registration::resampleOnto(ct, mr, moving, last.mrFromCt, &rr));
    const double fusionSeconds = seconds(t0);
    const double peakAboveLoadedMb = peakRssMb() - loadedMb;
    const auto t1 = Clock::now();
    segmentation::labelFused(fused, volume::TissueTable::builtin(), volume::FieldStrength::T1_5);
    const double labelSeconds = seconds(t1);

    const double denseMb = double(ct.indexBox().voxelCount()) * 4.0 / (1 << 20);
    out["voxhap_registration_s"] = stats(ours);
    out["voxhap_search_s"] = stats(search);
    out["elastix_s"] = stats(theirs);
    out["voxhap_over_elastix"] = stats(ratio);
    out["agreement_mean_mm"] = stats(agreement);
    out["fusion_after_registration_s"] = fusionSeconds;
    out["labels_from_both_scans_s"] = labelSeconds;
    out["resampled_voxels"] = rr.activeVoxels;
    out["rss_loaded_mb"] = loadedMb;
    out["peak_above_loaded_mb"] = peakAboveLoadedMb;
    out["dense_ct_float_mb"] = denseMb;
    out["peak_above_loaded_dense_ct_copies"] = peakAboveLoadedMb / denseMb;
    out["voxhap_started_from"] = last.startedFrom;
    return out;
}

nlohmann::json phantom(const std::string& kind, const std::string& elastix, int repeats, const fs::path& work)
{
    const auto& table = volume::TissueTable::builtin();
    volume::PhantomSpec spec;
    spec.kind = kind;
    const volume::PhantomModel model = volume::phantomModel(spec, table);
    volume::GridSpec grid;
    grid.spacing = Vec3d(1, 1, 1);
    volume::PhantomMrScan scan;
    // The issue's largest move: 15° about every axis and up to 30 mm.
    scan.rotation = (Eigen::AngleAxisd(0.2618, Vec3d::UnitZ()) * Eigen::AngleAxisd(0.2618, Vec3d::UnitY()) *
        Eigen::AngleAxisd(0.2618, Vec3d::UnitX()))
                        .toRotationMatrix();
    scan.translationMm = Vec3d(20, -15, 30);
    volume::PhantomScanTruth truth;
    const volume::Volume ct = volume::phantomCtScan(model, grid, table);
    const volume::Volume mr = volume::phantomMrScan(model, table, scan, &truth);
    const fs::path d = work / kind;
    fs::create_directories(d);
    volume::saveNrrd(ct, volume::Channel::Hu, d / "ct.nrrd", volume::NrrdEncoding::Raw);
    volume::saveNrrd(mr, volume::Channel::T1, d / "mr.nrrd", volume::NrrdEncoding::Raw);
    const std::vector<Vec3d> points = bodyPoints(ct, 3);
    const registration::AffineMap exact{truth.linear, truth.offset};

    // Interleaved repeats, as on the porcine pair; the errors are the last
    // repeat's (voxhap's answer repeats to the bit).
    std::vector<double> ours, search, after, theirs, ratio;
    registration::RegistrationResult last;
    ElastixRun e;
    for (int r = 0; r < repeats; ++r) {
        last = registration::registerMrToCt(ct, mr);
        ours.push_back(last.seconds);
        search.push_back(last.searchSeconds);
        after.push_back(last.seconds - last.searchSeconds);
        writeElastixInitial(last.start, d / "initial.txt");
        e = runElastix(elastix, d / "ct.nrrd", d / "mr.nrrd", d / "initial.txt", d / "el");
        theirs.push_back(e.seconds);
        ratio.push_back(after.back() / e.seconds);
    }
    const registration::AffineMap theirs0 = readElastixAnswer(e.parameters, last.start);
    const auto [oursMean, oursMax] = distance(last.mrFromCt, exact, points);
    const auto [theirMean, theirMax] = distance(theirs0, exact, points);
    return {{"voxhap_registration_s", stats(ours)}, {"voxhap_search_s", stats(search)},
        {"voxhap_after_search_s", stats(after)}, {"elastix_from_voxhaps_start_s", stats(theirs)},
        {"voxhap_after_search_over_elastix", stats(ratio)}, {"voxhap_tre_mm", {{"mean", oursMean}, {"max", oursMax}}},
        {"elastix_tre_mm", {{"mean", theirMean}, {"max", theirMax}}}, {"body_points", points.size()}};
}

} // namespace

int main(int argc, char** argv)
{
    int repeats = 3;
    bool json = false;
    std::string elastix = "elastix";
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--repeats") && i + 1 < argc) {
            repeats = std::max(1, std::atoi(argv[++i]));
        } else if (!std::strcmp(argv[i], "--elastix") && i + 1 < argc) {
            elastix = argv[++i];
        } else if (!std::strcmp(argv[i], "--json")) {
            json = true;
        } else {
            std::cerr << "usage: bench_fusion [--repeats N] [--json] [--elastix PROGRAM]\n";
            return 2;
        }
    }
    if (std::system(("command -v " + elastix + " > /dev/null 2>&1").c_str()) != 0) {
        std::cerr << "bench_fusion: no '" << elastix
                  << "' on PATH (Debian package elastix; tools/setup.sh installs it)\n";
        return 1;
    }
    const fs::path work = fs::temp_directory_path() / ("voxhap-bench-fusion-" + std::to_string(::getpid()));
    fs::create_directories(work);
    nlohmann::json out;
    try {
        out["machine"] = {
            {"hardware_threads", std::thread::hardware_concurrency()}, {"load_average_before", loadAverage()}};
        out["pyramid"] = "voxhap: 3 levels, finest 1.2 mm, block averages; elastix: 3 levels of its recursive "
                         "pyramid, full resolution last (tests/registration/elastix/rigid-mattes.txt)";
        out["porcine"] = porcine(elastix, repeats, work);
        out["lumbar"] = phantom("lumbar", elastix, repeats, work);
        out["torso"] = phantom("torso", elastix, repeats, work);
        out["machine"]["load_average_after"] = loadAverage();
    } catch (const std::exception& e) {
        fs::remove_all(work);
        std::cerr << "bench_fusion: " << e.what() << '\n';
        return 1;
    }
    fs::remove_all(work);
    if (json) {
        std::cout << out.dump(2) << '\n';
        return 0;
    }
    const auto& p = out["porcine"];
    if (p.contains("skipped")) {
        std::cout << "porcine: " << p["skipped"].get<std::string>() << '\n';
    } else {
        std::cout << "porcine pair, " << repeats << " interleaved repeats (medians):\n"
                  << "  voxhap rigid registration " << p["voxhap_registration_s"]["median"].get<double>()
                  << " s (orientation search " << p["voxhap_search_s"]["median"].get<double>() << " s)\n"
                  << "  elastix, 2 threads        " << p["elastix_s"]["median"].get<double>() << " s\n"
                  << "  voxhap / elastix          " << p["voxhap_over_elastix"]["median"].get<double>() << '\n'
                  << "  agreement over the body   " << p["agreement_mean_mm"]["median"].get<double>() << " mm mean\n"
                  << "  fusion after registration " << p["fusion_after_registration_s"].get<double>()
                  << " s (resampling, the grids; the labels from both scans "
                  << p["labels_from_both_scans_s"].get<double>() << " s more)\n"
                  << "  peak memory above the loaded volumes " << p["peak_above_loaded_mb"].get<double>()
                  << " MiB = " << p["peak_above_loaded_dense_ct_copies"].get<double>() << " dense float CT copies\n";
    }
    for (const char* kind : {"lumbar", "torso"}) {
        const auto& k = out[kind];
        std::cout << kind << " phantom, MR turned 15° about each axis and moved (20, −15, 30) mm, " << repeats
                  << " interleaved repeats (medians):\n"
                  << "  voxhap " << k["voxhap_registration_s"]["median"].get<double>() << " s (after its search "
                  << k["voxhap_after_search_s"]["median"].get<double>() << " s), TRE mean "
                  << k["voxhap_tre_mm"]["mean"].get<double>() << " mm, max " << k["voxhap_tre_mm"]["max"].get<double>()
                  << " mm\n"
                  << "  elastix from voxhap's start " << k["elastix_from_voxhaps_start_s"]["median"].get<double>()
                  << " s, TRE mean " << k["elastix_tre_mm"]["mean"].get<double>() << " mm, max "
                  << k["elastix_tre_mm"]["max"].get<double>() << " mm\n"
                  << "  voxhap after its search / elastix "
                  << k["voxhap_after_search_over_elastix"]["median"].get<double>() << '\n';
    }
    std::cout << "load average " << out["machine"]["load_average_before"].get<double>() << " before, "
              << out["machine"]["load_average_after"].get<double>() << " after (2 cores: above 2, other processes "
              << "took CPU)\n";
    return 0;
}
