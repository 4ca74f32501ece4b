// SPDX-License-Identifier: Apache-2.0
/// @file TestFusedMaterial.cpp
/// @brief A fused CT and MR's material (physics.md §5.5): β from T1 in fat and
/// muscle where the t1 grid is active, the table's β by label everywhere else
/// (outside the MR's field of view, and in every other tissue), bone stiffness
/// from HU; and the report of which voxels took which source.

#include "common/BuiltinTable.h"

#include "haptic/materials/FieldGrids.h"
#include "haptic/materials/MaterialField.h"
#include "phantoms/Phantoms.h"

#include <cmath>

namespace voxhap::haptic {
namespace {

using voxhap::test::table;

/// Eq. 4 at 1.5 T with physics.md §5.4's printed constants (as TestMaterialField.cpp).
double beta15T(double t1Ms) { return 2464e-6 * std::exp(1.398e-3 * t1Ms); }
/// Four printed digits of C1 and C2: the law is reproduced to about 7e-4 relative.
constexpr double kFitRounding = 1e-3;

TEST(FusedMaterial, T1DrivesFatAndMuscleOnlyWhereTheMrSeesThem)
{
    // The lumbar phantom's labels and HU; a T1 map over the half x < 0 only, with
    // fat and muscle at T1 values the table does not hold (so that a table value
    // cannot pass for Eq. 4's).
    volume::LumbarParams lp;
    lp.grid.spacing = Vec3d(1.0, 1.0, 1.0);
    volume::Volume v = volume::makePhantom(volume::lumbarModel(lp, table()), lp.grid, table());
    const int fat = table().at("fat").id, muscle = table().at("muscle").id;
    const double fatT1 = 350.0, muscleT1 = 700.0;
    auto labels = volume::labelGrid(v);
    auto t1 = volume::FloatGrid::create(volume::kAirT1);
    {
        auto la = labels->getConstAccessor();
        auto ta = t1->getAccessor();
        const auto& b = v.indexBox();
        for (int k = b.min.z(); k <= b.max.z(); ++k)
            for (int j = b.min.y(); j <= b.max.y(); ++j)
                for (int i = b.min.x(); i <= b.max.x(); ++i) {
                    const openvdb::Coord c(i, j, k);
                    if (v.indexToWorld(Vec3d(i, j, k)).x() >= 0.0 || !la.isValueOn(c)) continue;
                    const int l = la.getValue(c);
                    ta.setValueOn(c, l == fat ? float(fatT1) : l == muscle ? float(muscleT1) : 1234.0f);
                }
    }
    v.setGrid(volume::Channel::T1, t1);

    MaterialOptions o;
    o.field = volume::FieldStrength::T1_5;
    o.needs.boneStiffness = true;
    const MaterialField f(v, table(), o);
    const auto beta = detail::dampingGrid(f);
    auto ba = beta->getConstAccessor();
    auto la = labels->getConstAccessor();
    std::int64_t fromT1 = 0, fromTable = 0, checked[4] = {0, 0, 0, 0};
    for (auto it = labels->cbeginValueOn(); it; ++it) {
        openvdb::CoordBBox box;
        it.getBoundingBox(box);
        for (auto c = box.begin(); c; ++c) {
            const int l = *it;
            const bool seen = v.indexToWorld(Vec3d((*c).x(), (*c).y(), (*c).z())).x() < 0.0;
            const double got = ba.getValue(*c);
            if (seen && (l == fat || l == muscle)) {
                const double want = beta15T(l == fat ? fatT1 : muscleT1);
                ASSERT_NEAR(got, want, kFitRounding * want) << "Eq. 4 where T1 exists";
                ++fromT1;
                ++checked[l == fat ? 0 : 1];
            } else {
                const auto& d = table().at(l).damping; // the table by label; none: 0
                const double want = d ? d->value : 0.0;
                ASSERT_NEAR(got, want, 1e-9) << table().at(l).name << (seen ? " (seen by the MR)" : "");
                ++fromTable;
                ++checked[seen ? 2 : 3];
            }
        }
    }
    // Every case occurred: T1 for fat and muscle, the table for other tissue under
    // the MR, and for everything outside it.
    for (std::int64_t n : checked) EXPECT_GT(n, 0);
    EXPECT_EQ(f.dampingSources().fromT1Voxels, fromT1);
    EXPECT_EQ(f.dampingSources().fromTableVoxels, fromTable);
    // Bone stiffness comes from HU whatever the MR says.
    EXPECT_GT(f.stiffnessReport().boneVoxels, 0);
}

} // namespace
} // namespace voxhap::haptic
