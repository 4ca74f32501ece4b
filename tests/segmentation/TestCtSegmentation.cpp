// SPDX-License-Identifier: Apache-2.0
/// @file TestCtSegmentation.cpp
/// @brief CT segmentation of the torso phantom (physics.md §1.1), generated
/// from the tissue table with scanner noise: each needle-relevant class
/// recovered with Dice ≥ 0.95 on its own (issue 7), the soft tissues CT cannot
/// separate from muscle as one class, distance fields written.

#include "SegmentationFixtures.h"

#include "phantoms/Phantoms.h"
#include "segmentation/DistanceField.h"
#include "segmentation/Segmentation.h"
#include "volume/Grids.h"

#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <ostream>
#include <set>
#include <string>
#include <vector>

namespace voxhap::segmentation {
namespace {

using test::enhancedTable;

// CT quantum noise in soft tissue [HU]: the upper end of a routine abdominal scan.
constexpr double kNoiseHu = 20.0;

struct TorsoCase {
    std::unique_ptr<volume::Volume> v;
    volume::LabelGrid::Ptr truth;
    SegmentReport report;
};

const TorsoCase& torso()
{
    static const TorsoCase c = [] {
        TorsoCase t;
        const auto& table = enhancedTable();
        volume::TorsoParams p;
        // 0.5 mm in-plane keeps the 2 mm skin 4 voxels thick; 3 mm slices like the test CT.
        p.grid.spacing = Vec3d(0.5, 0.5, 3.0);
        t.v = std::make_unique<volume::Volume>(volume::makePhantom(volume::torsoModel(p, table), p.grid, table));
        t.truth = openvdb::gridPtrCast<volume::LabelGrid>(t.v->grid(volume::Channel::Label)->deepCopyGrid());
        auto hu = openvdb::gridPtrCast<volume::FloatGrid>(t.v->grid(volume::Channel::Hu)->deepCopyGrid());
        test::addNoise(*hu, kNoiseHu, 11);
        t.v->setGrid(volume::Channel::Hu, hu);
        t.v->removeGrid(volume::Channel::Label);
        t.v->removeGrid(volume::Channel::T1);
        t.report = segment(*t.v, table);
        return t;
    }();
    return c;
}

/// One class of the Dice check: the truth labels and the result labels that count as it.
struct DiceClass {
    std::string name;
    std::vector<std::string> truth, result;
};

void PrintTo(const DiceClass& c, std::ostream* os) { *os << c.name; }

/// The classes a needle meets or must avoid on the torso (physics.md §1.1), each on
/// its own: skin, fat and muscle on the way in, the bone it stops on and the lesion's
/// bone, and the critical structures lung, kidney and aorta; air around the body.
const std::vector<DiceClass>& needleClasses()
{
    static const std::vector<DiceClass> c{
        {"air", {"air"}, {"air"}},
        {"skin", {"skin"}, {"skin"}},
        {"fat", {"fat"}, {"fat"}},
        {"muscle", {"muscle"}, {"muscle"}},
        {"lung", {"lung"}, {"lung"}},
        {"kidney", {"kidney"}, {"kidney"}},
        {"aorta", {"aorta"}, {"aorta"}},
        {"cortical_bone", {"cortical_bone"}, {"cortical_bone"}},
        {"cancellous_bone", {"cancellous_bone"}, {"cancellous_bone"}},
    };
    return c;
}

std::set<int> idsOf(const std::vector<std::string>& names)
{
    std::set<int> ids;
    for (const auto& n : names) ids.insert(n == "air" ? 0 : enhancedTable().at(n).id);
    return ids;
}

double diceOf(const DiceClass& k)
{
    const TorsoCase& c = torso();
    const auto result = volume::labelGrid(*c.v);
    if (!result) return 0.0;
    return test::dice(*c.truth, *result, c.v->indexBox(), idsOf(k.truth), idsOf(k.result));
}

class CtSegmentationClass : public testing::TestWithParam<DiceClass> { };

TEST_P(CtSegmentationClass, TorsoPhantomDiceAtLeast095)
{
    EXPECT_EQ(torso().report.method, "ct");
    const double d = diceOf(GetParam());
    EXPECT_GE(d, test::kMinDice) << GetParam().name;
    std::cout << "dice " << GetParam().name << " " << d << "\n";
}

INSTANTIATE_TEST_SUITE_P(NeedleRelevant, CtSegmentationClass, testing::ValuesIn(needleClasses()),
    [](const testing::TestParamInfo<DiceClass>& i) { return i.param.name; });

// The phantom's soft tissues that CT numbers cannot tell from muscle (ligaments, dura,
// CSF, cord, disc, the lytic lesion, the epidural space) are checked only as one class
// with muscle; the result's soft_tissue and spinal_cord belong to it too (the canal
// is tested on the real CT). This is a check of the merged class, not of its members.
TEST(CtSegmentation, TorsoPhantomLeanSoftTissueAsOneClassDiceAtLeast095)
{
    const std::vector<std::string> lean{"muscle", "supraspinous_ligament", "interspinous_ligament", "ligamentum_flavum",
        "dura", "csf", "spinal_cord", "intervertebral_disc", "lesion", "soft_tissue", "epidural_space"};
    const double d = diceOf({"lean soft tissue", lean, lean});
    EXPECT_GE(d, test::kMinDice);
    std::cout << "dice lean soft tissue " << d << "\n";
}

TEST(CtSegmentation, DistanceFieldsOfTheCriticalStructuresPresent)
{
    const TorsoCase& c = torso();
    // No spinal canal here: it is found as the hole of a closed bony ring (pedicles,
    // laminae), and the phantom's arch does not join its vertebral body. The real-CT
    // test checks the canal.
    for (const char* name : {"lung", "kidney", "aorta"}) {
        const auto g = openvdb::gridConstPtrCast<volume::FloatGrid>(c.v->derived(distanceFieldName(name)));
        ASSERT_TRUE(g) << name;
    }
    // The aorta's axis is 11 mm inside its wall; the lesion centre lies 33 mm from
    // the aorta's axis, 22 mm from its wall (TorsoPhantom.cpp): both well inside the
    // 30 mm band. Tolerance: 2 mm, the voxels' half diagonal (1.6 mm) rounded up.
    const auto sdf = openvdb::gridConstPtrCast<volume::FloatGrid>(c.v->derived(distanceFieldName("aorta")));
    const auto sample = [&](const Vec3d& w) {
        const Vec3d ijk = c.v->worldToIndex(w);
        return sdf->getConstAccessor().getValue(
            openvdb::Coord(int(std::lround(ijk.x())), int(std::lround(ijk.y())), int(std::lround(ijk.z()))));
    };
    const Vec3d aorta = *volume::phantomLandmark(*c.v, "aorta");
    const Vec3d lesion = *volume::phantomLandmark(*c.v, "lesion");
    EXPECT_NEAR(sample(aorta), -11.0, 2.0);
    EXPECT_NEAR(sample(lesion), (lesion - aorta).head<2>().norm() - 11.0, 2.0);
}

TEST(CtSegmentation, SummaryVolumesMatchTheVoxelCounts)
{
    const TorsoCase& c = torso();
    const double voxelMl = 0.5 * 0.5 * 3.0 * 1e-3;
    ASSERT_FALSE(c.report.labels.empty());
    for (const auto& l : c.report.labels) {
        EXPECT_NEAR(l.ml, double(l.voxels) * voxelMl, 1e-9 * l.ml) << l.name;
        EXPECT_LE(l.bounds[0].x(), l.bounds[1].x());
    }
}

} // namespace
} // namespace voxhap::segmentation
