// SPDX-License-Identifier: Apache-2.0
/// @file Resample.cpp
/// @brief The MR's leaves mapped into the CT's index space give the candidate
/// voxels; each candidate reads the MR trilinearly (OpenVDB's BoxSampler).

#include "registration/Resample.h"

#include "core/Errors.h"
#include "registration/LevelImage.h"
#include "volume/Grids.h"

#include <openvdb/tools/Interpolation.h>
#include <openvdb/tree/LeafManager.h>

#include <chrono>
#include <cmath>

namespace voxhap::registration {

using volume::FloatGrid;

namespace {

/// The affine map from CT index to MR index: mrIndex = M·ctIndex + b.
struct IndexMap {
    Mat3d m;
    Vec3d b;
    Vec3d operator()(const Vec3d& ijk) const { return m * ijk + b; }
};

IndexMap indexMap(const volume::Volume& ct, const volume::Volume& mr, const AffineMap& mrFromCt)
{
    const volume::Geometry gc = ct.geometry(), gm = mr.geometry();
    const Mat3d ctToWorld = gc.direction * gc.spacing.asDiagonal();
    const Mat3d worldToMr = gm.spacing.cwiseInverse().asDiagonal() * gm.direction.transpose();
    IndexMap im;
    im.m = worldToMr * mrFromCt.linear * ctToWorld;
    im.b = worldToMr * (mrFromCt.linear * gc.origin + mrFromCt.offset - gm.origin);
    return im;
}

} // namespace

volume::Volume::GridPtr resampleOnto(const volume::Volume& ct, const volume::Volume& mr, volume::Channel c,
    const AffineMap& mrFromCt, ResampleReport* report)
{
    const auto t0 = std::chrono::steady_clock::now();
    volume::initializeOpenVdb();
    const float background = backgroundOf(c);
    const auto source = openvdb::gridConstPtrCast<FloatGrid>(mr.grid(c));
    if (!source) throw ValueError("resampling: the MR has no " + std::string(volume::channelName(c)) + " grid");

    const IndexMap toMr = indexMap(ct, mr, mrFromCt);
    const AffineMap toCtIndex = [&] {
        // MR index → CT index: the inverse of toMr.
        const Mat3d inv = toMr.m.inverse();
        return AffineMap{inv, -(inv * toMr.b)};
    }();
    const openvdb::CoordBBox ctBox = volume::toCoordBBox(ct.indexBox());

    // Candidates: every MR node with active values, its index box (grown by
    // half a voxel to its faces) mapped into the CT's index space.
    auto candidates = openvdb::MaskGrid::create(false);
    auto addBox = [&](const openvdb::CoordBBox& mrBox) {
        Vec3d lo = Vec3d::Constant(1e300), hi = Vec3d::Constant(-1e300);
        for (int corner = 0; corner < 8; ++corner) {
            const Vec3d p((corner & 1) ? mrBox.max().x() + 0.5 : mrBox.min().x() - 0.5,
                (corner & 2) ? mrBox.max().y() + 0.5 : mrBox.min().y() - 0.5,
                (corner & 4) ? mrBox.max().z() + 0.5 : mrBox.min().z() - 0.5);
            const Vec3d q = toCtIndex.apply(p);
            lo = lo.cwiseMin(q);
            hi = hi.cwiseMax(q);
        }
        openvdb::CoordBBox box(
            openvdb::Coord(int(std::floor(lo.x())), int(std::floor(lo.y())), int(std::floor(lo.z()))),
            openvdb::Coord(int(std::ceil(hi.x())), int(std::ceil(hi.y())), int(std::ceil(hi.z()))));
        box.intersect(ctBox);
        if (!box.empty()) candidates->tree().sparseFill(box, true, true);
    };
    for (auto leaf = source->tree().cbeginLeaf(); leaf; ++leaf) {
        if (!leaf->isEmpty()) addBox(leaf->getNodeBoundingBox());
    }
    {
        auto it = source->tree().cbeginValueOn();
        it.setMaxDepth(FloatGrid::TreeType::ValueOnCIter::LEAF_DEPTH - 1);
        for (; it; ++it) {
            openvdb::CoordBBox tile;
            it.getBoundingBox(tile);
            addBox(tile);
        }
    }

    auto tree = std::make_shared<FloatGrid::TreeType>(candidates->tree(), background, openvdb::TopologyCopy());
    tree->voxelizeActiveTiles();
    candidates.reset();
    openvdb::tree::LeafManager<FloatGrid::TreeType> leaves(*tree);
    leaves.foreach ([&](FloatGrid::TreeType::LeafNodeType& leaf, std::size_t) {
        auto acc = source->getConstAccessor();
        for (auto it = leaf.beginValueOn(); it; ++it) {
            const openvdb::Coord ijk = it.getCoord();
            const Vec3d p = toMr(Vec3d(ijk.x(), ijk.y(), ijk.z()));
            const openvdb::Coord nearest(int(std::lround(p.x())), int(std::lround(p.y())), int(std::lround(p.z())));
            if (!acc.isValueOn(nearest)) {
                it.setValue(background);
                it.setValueOn(false);
                continue;
            }
            it.setValue(openvdb::tools::BoxSampler::sample(acc, openvdb::Vec3R(p.x(), p.y(), p.z())));
        }
    });
    tree->prune(); // exact: tolerance 0
    auto grid = FloatGrid::create(tree);
    grid->setTransform(ct.transform().copy());
    if (report) {
        report->activeVoxels = std::int64_t(grid->activeVoxelCount());
        report->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    return grid;
}

} // namespace voxhap::registration
