// SPDX-License-Identifier: Apache-2.0
/// @file Rasterize.cpp
/// @brief Leaf-by-leaf parallel sampling of an analytic classifier into sparse grids.

#include "phantoms/Rasterize.h"

#include "core/Errors.h"
#include "volume/Grids.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <memory>

namespace voxhap::volume {

namespace {

using FloatLeaf = FloatGrid::TreeType::LeafNodeType;
using LabelLeaf = LabelGrid::TreeType::LeafNodeType;
constexpr int kLeafDim = int(FloatLeaf::DIM); // 8 voxels per leaf side

/// The index box of the voxels whose cells meet the world box: a voxel with
/// centre c covers [c - 1/2, c + 1/2] in index space.
IndexBox coveringBox(const WorldBox& b, const Mat3d& indexToWorldLinear)
{
    const Mat3d inv = indexToWorldLinear.inverse();
    Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::infinity());
    Vec3d hi = -lo;
    for (int corner = 0; corner < 8; ++corner) {
        Vec3d w;
        for (int a = 0; a < 3; ++a) w[a] = ((corner >> a) & 1) ? b.max[a] : b.min[a];
        const Vec3d p = inv * w - Vec3d::Constant(0.5); // centres are at n + 1/2 in lattice units
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    IndexBox box;
    for (int a = 0; a < 3; ++a) {
        // c > lo - 1/2 and c < hi + 1/2, with a little slack for round-off.
        box.min[a] = int(std::floor(lo[a] - 0.5 + 1e-9)) + 1;
        box.max[a] = int(std::ceil(hi[a] + 0.5 - 1e-9)) - 1;
    }
    return box;
}

} // namespace

Volume rasterize(const Classifier& classify, const WorldBox& bounds, const GridSpec& spec, const TissueTable& table)
{
    Geometry g;
    g.spacing = spec.spacing;
    g.direction = spec.direction;
    const Mat3d linear = spec.direction * spec.spacing.asDiagonal();
    g.origin = linear * Vec3d::Constant(0.5); // anchor the lattice's faces at the world origin
    auto xform = makeTransform(g);            // validates spacing and direction
    const IndexBox box = coveringBox(bounds, linear);
    if (box.empty()) throw ValueError("phantom: empty extent");
    const std::int64_t kMaxVoxels = std::int64_t(1) << 34; // 16 Gi voxels: refuse absurd requests early
    if (box.voxelCount() > kMaxVoxels) {
        throw ValueError(
            "phantom: " + std::to_string(box.voxelCount()) + " voxels at this spacing; use a coarser --spacing");
    }

    // Per-id lookup tables so that the inner loop does no map search.
    const int maxId = table.maxId();
    std::vector<float> huOf(std::size_t(maxId) + 1, kAirHu), t1Of(std::size_t(maxId) + 1, kAirT1);
    std::vector<char> known(std::size_t(maxId) + 1, 0);
    for (const auto& t : table.tissues()) {
        huOf[std::size_t(t.id)] = float(t.huTypical);
        t1Of[std::size_t(t.id)] = float(t.t1(spec.field));
        known[std::size_t(t.id)] = 1;
    }

    // Leaf origins (multiples of 8) that cover the box.
    std::vector<openvdb::Coord> origins;
    const Vec3i lo = box.min.unaryExpr([](int v) { return v & ~(kLeafDim - 1); });
    for (int x = lo.x(); x <= box.max.x(); x += kLeafDim)
        for (int y = lo.y(); y <= box.max.y(); y += kLeafDim)
            for (int z = lo.z(); z <= box.max.z(); z += kLeafDim) origins.emplace_back(x, y, z);

    struct Leaves {
        std::unique_ptr<LabelLeaf> label;
        std::unique_ptr<FloatLeaf> hu, t1;
    };
    std::vector<Leaves> leaves(origins.size());
    std::atomic<int> badId{-1};
    const openvdb::CoordBBox cbox = toCoordBBox(box);

    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, origins.size()), [&](const auto& range) {
        std::array<int, FloatLeaf::SIZE> ids;
        for (std::size_t n = range.begin(); n != range.end(); ++n) {
            const openvdb::Coord& o = origins[n];
            bool any = false;
            for (int i = 0; i < kLeafDim; ++i)
                for (int j = 0; j < kLeafDim; ++j)
                    for (int k = 0; k < kLeafDim; ++k) {
                        const openvdb::Coord c = o.offsetBy(i, j, k);
                        const auto offset = FloatLeaf::coordToOffset(c);
                        int id = 0;
                        if (cbox.isInside(c)) {
                            id = classify(g.origin + linear * Vec3d(c.x(), c.y(), c.z()));
                            if (id < 0 || id > maxId || !known[std::size_t(id)]) {
                                badId = id;
                                id = 0;
                            }
                        }
                        ids[offset] = id;
                        any |= id != 0;
                    }
            if (!any) continue;
            Leaves& l = leaves[n];
            l.label = std::make_unique<LabelLeaf>(o, kAirLabel, false);
            l.hu = std::make_unique<FloatLeaf>(o, kAirHu, false);
            l.t1 = std::make_unique<FloatLeaf>(o, kAirT1, false);
            for (openvdb::Index off = 0; off < FloatLeaf::SIZE; ++off) {
                const int id = ids[off];
                if (id == 0) continue;
                l.label->setValueOn(off, id);
                l.hu->setValueOn(off, huOf[std::size_t(id)]);
                l.t1->setValueOn(off, t1Of[std::size_t(id)]);
            }
        }
    });
    if (badId.load() != -1) {
        throw ValueError("phantom: classifier produced tissue id " + std::to_string(badId.load()) + " that " +
            table.origin() + " does not hold");
    }

    auto labelGridPtr = LabelGrid::create(kAirLabel);
    auto huGridPtr = FloatGrid::create(kAirHu);
    auto t1GridPtr = FloatGrid::create(kAirT1);
    for (auto& l : leaves) {
        if (!l.label) continue;
        labelGridPtr->tree().addLeaf(l.label.release());
        huGridPtr->tree().addLeaf(l.hu.release());
        t1GridPtr->tree().addLeaf(l.t1.release());
    }
    // Uniform leaves become tiles: exact (tolerance 0), and most of a phantom is uniform.
    labelGridPtr->tree().prune();
    huGridPtr->tree().prune();
    t1GridPtr->tree().prune();

    Volume v(xform, box);
    v.setGrid(Channel::Label, labelGridPtr);
    v.setGrid(Channel::Hu, huGridPtr);
    v.setGrid(Channel::T1, t1GridPtr);
    VolumeMetadata& md = v.metadata();
    md.modality = "phantom";
    md.modalitySource = FactSource::Generator;
    md.t1Units = "ms";
    md.t1Kind = T1Kind::Map; // the table's T1 at the spec's field, as a T1 map would give it
    md.fieldStrength = spec.field;
    md.fieldStrengthSource = FactSource::Generator;
    return v;
}

std::vector<LayerSpan> traceLayers(const Classifier& classify, const Vec3d& entry, const Vec3d& direction,
    double length, const TissueTable& table, double stepMm)
{
    std::vector<LayerSpan> out;
    const double norm = direction.norm();
    if (!(norm > 0.0) || !(length > 0.0) || !(stepMm > 0.0)) return out;
    const Vec3d d = direction / norm;
    auto at = [&](double s) { return classify(entry + s * d); };
    const auto nameOf = [&](int id) {
        const Tissue* t = table.find(id);
        return t ? t->name : std::string("unknown");
    };
    int current = at(0.0);
    double start = 0.0;
    double s = 0.0;
    while (s < length) {
        const double next = std::min(length, s + stepMm);
        if (at(next) == current) {
            s = next;
            continue;
        }
        double a = s, b = next; // at(a) == current, at(b) != current
        while (b - a > 1e-9) {
            const double m = 0.5 * (a + b);
            (at(m) == current ? a : b) = m;
        }
        if (b - start > 1e-9) out.push_back({current, nameOf(current), start, b});
        current = at(b);
        start = b;
        s = b; // rescan from the boundary: a thin layer may end within the same step
    }
    if (length - start > 1e-9) out.push_back({current, nameOf(current), start, length});
    return out;
}

} // namespace voxhap::volume
