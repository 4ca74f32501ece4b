// SPDX-License-Identifier: Apache-2.0
/// @file PhantomScans.cpp
/// @brief The MR scan of a phantom: the analytic classifier sampled through
/// the inverse of the body's move, averaged per voxel, with Rician noise.

#include "phantoms/PhantomScans.h"

#include "core/AtomicFile.h"
#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/io/NrrdFile.h"
#include "volume/mr/MrWeighting.h"

#include <nlohmann/json.hpp>
#include <openvdb/tools/Dense.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <random>

namespace voxhap::volume {

namespace {

/// Air beyond the moved body's box in the MR's field of view [mm] [chosen:
/// the body is well inside, as a technician frames a scan].
constexpr double kMrMarginMm = 10.0;

} // namespace

Volume phantomCtScan(const PhantomModel& model, const GridSpec& grid, const TissueTable& table)
{
    Volume full = makePhantom(model, grid, table);
    Volume ct(full.transformPtr()->copy(), full.indexBox());
    ct.setGrid(Channel::Hu, std::const_pointer_cast<openvdb::GridBase>(full.grid(Channel::Hu))->copyGrid());
    ct.metadata() = full.metadata();
    ct.metadata().modality = "CT";
    ct.metadata().description = "CT scan of the " + model.kind + " phantom";
    return ct;
}

Volume phantomMrScan(
    const PhantomModel& model, const TissueTable& table, const PhantomMrScan& scan, PhantomScanTruth* truth)
{
    initializeOpenVdb();
    if ((scan.spacing.array() <= 0.0).any() || !scan.spacing.allFinite()) {
        throw ValueError("phantom MR: the spacing must be positive");
    }
    if (scan.supersample < 1) throw ValueError("phantom MR: supersample must be at least 1");
    const Vec3d centre = 0.5 * (model.bounds.min + model.bounds.max);
    PhantomScanTruth t;
    t.linear = scan.rotation;
    t.offset = centre - scan.rotation * centre + scan.translationMm;
    if (truth) *truth = t;

    // The MR's field of view: the moved body's box, with a margin.
    Vec3d lo = Vec3d::Constant(1e300), hi = Vec3d::Constant(-1e300);
    for (int corner = 0; corner < 8; ++corner) {
        Vec3d w;
        for (int a = 0; a < 3; ++a) w[a] = ((corner >> a) & 1) ? model.bounds.max[a] : model.bounds.min[a];
        const Vec3d y = t.apply(w);
        lo = lo.cwiseMin(y);
        hi = hi.cwiseMax(y);
    }
    lo -= Vec3d::Constant(kMrMarginMm);
    hi += Vec3d::Constant(kMrMarginMm);
    Geometry g;
    g.spacing = scan.spacing;
    g.origin = lo + 0.5 * scan.spacing;
    const Vec3i dims = ((hi - lo).cwiseQuotient(scan.spacing)).array().ceil().cast<int>().max(1);
    IndexBox box{Vec3i::Zero(), dims - Vec3i::Ones()};

    std::vector<float> t1Of(std::size_t(table.maxId()) + 1, kAirT1);
    for (const auto& tissue : table.tissues()) t1Of[std::size_t(tissue.id)] = float(tissue.t1(scan.field));
    const double sigma = scan.noiseOfMuscleT1 * table.at("muscle").t1(scan.field);
    const Mat3d back = t.linear.inverse();
    const int n = scan.supersample;

    std::vector<float> values(std::size_t(box.voxelCount()));
    tbb::parallel_for(0, dims.z(), [&](int k) {
        // One generator per slice, seeded from the scan's seed and the slice:
        // the same image whatever the threads.
        std::mt19937_64 rng(scan.seed * 1000003ULL + std::uint64_t(k));
        std::normal_distribution<double> noise(0.0, sigma);
        for (int j = 0; j < dims.y(); ++j) {
            for (int i = 0; i < dims.x(); ++i) {
                double sum = 0.0;
                for (int c = 0; c < n; ++c) {
                    for (int b = 0; b < n; ++b) {
                        for (int a = 0; a < n; ++a) {
                            const Vec3d sub((a + 0.5) / n - 0.5, (b + 0.5) / n - 0.5, (c + 0.5) / n - 0.5);
                            const Vec3d y = g.origin + g.spacing.cwiseProduct(Vec3d(i, j, k) + sub);
                            const Vec3d x = back * (y - t.offset);
                            // The body ends at the model's bounds, as in the CT: the
                            // analytic layers themselves run on without end.
                            const bool inBody = (x.array() >= model.bounds.min.array()).all() &&
                                (x.array() <= model.bounds.max.array()).all();
                            const int id = inBody ? model.classify(x) : 0;
                            sum += double(id >= 0 && std::size_t(id) < t1Of.size() ? t1Of[std::size_t(id)] : kAirT1);
                        }
                    }
                }
                const double s = sum / double(n * n * n);
                const double re = s + noise(rng), im = noise(rng);
                values[std::size_t((std::int64_t(k) * dims.y() + j) * dims.x() + i)] = float(std::hypot(re, im));
            }
        }
    });
    auto grid = FloatGrid::create(kAirT1);
    openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> dense(toCoordBBox(box), values.data());
    openvdb::tools::copyFromDense(dense, *grid, 0.0f);
    Volume mr(g, box);
    mr.setGrid(Channel::T1, grid);
    VolumeMetadata& md = mr.metadata();
    md.modality = "MR";
    md.mrWeighting = MrWeightingKind::T1Map;
    md.t1Kind = T1Kind::Map;
    recordFieldStrength(md, scan.field == FieldStrength::T3 ? 3.0 : 1.5, FactSource::Generator, scan.field);
    md.description = "MR T1 map of the " + model.kind + " phantom, moved, with Rician noise";
    return mr;
}

std::string phantomMrSidecar(FieldStrength field)
{
    nlohmann::json sidecar;
    sidecar["Modality"] = "MR";
    sidecar["MagneticFieldStrength"] = field == FieldStrength::T3 ? 3.0 : 1.5;
    sidecar["ImageType"] = {"DERIVED", "PRIMARY", "T1MAP"};
    sidecar["SeriesDescription"] = "T1 map (voxhap phantom)";
    return sidecar.dump(2) + '\n';
}

void writePhantomMrScan(const Volume& mr, FieldStrength field, const std::filesystem::path& nrrd)
{
    saveNrrd(mr, Channel::T1, nrrd, NrrdEncoding::Gzip, NrrdKeys::Plain);
    writeStreamAtomically(bidsSidecarPath(nrrd), [&](std::ostream& out) { out << phantomMrSidecar(field); });
}

} // namespace voxhap::volume
