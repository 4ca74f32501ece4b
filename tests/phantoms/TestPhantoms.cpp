// SPDX-License-Identifier: Apache-2.0
/// @file TestPhantoms.cpp
/// @brief Phantom layer boundaries against the physics.md numbers, voxel
/// consistency of hu/t1/label, sparsity, and the torso's anatomy.

#include "common/BuiltinTable.h"
#include "common/Tolerances.h"

#include "core/Errors.h"
#include "phantoms/Phantoms.h"
#include "volume/Grids.h"

#include <Eigen/Geometry>

#include <map>
#include <set>

namespace voxhap::volume {
namespace {

using test::halfVoxel;

using voxhap::test::table;

/// Tissue name of the voxel nearest to a world point (the voxel whose cell holds it).
std::string labelAt(const Volume& v, const Vec3d& world)
{
    const Vec3d ijk = v.worldToIndex(world);
    const openvdb::Coord c(int(std::lround(ijk.x())), int(std::lround(ijk.y())), int(std::lround(ijk.z())));
    return table().at(labelGrid(v)->getConstAccessor().getValue(c)).name;
}

struct Boundary {
    std::string below; ///< tissue on the deeper side
    double depth;      ///< [mm] along the path
};

/// Tissue transitions along entry + s·dir, sampled every 0.01 mm through the voxels.
std::vector<Boundary> voxelBoundaries(const Volume& v, const Vec3d& entry, const Vec3d& dir, double length)
{
    std::vector<Boundary> out;
    std::string current = labelAt(v, entry);
    for (double s = 0.01; s <= length; s += 0.01) {
        const std::string l = labelAt(v, entry + s * dir);
        if (l != current) out.push_back({l, s - 0.005});
        current = l;
    }
    return out;
}

/// Expected midline layers (name, thickness mm), from the numbers in physics.md:
/// skin 2 mm ([LP] §4), fat = derma - skin with derma from [S19] Table I (§2.3),
/// supraspinous 3 + interspinous 15 = [C-ui] 18 mm, flavum 7.4 mm [C-ui] (§3.2),
/// epidural from [S19] Table I, dura 1 mm [chosen], CSF 13 mm ([LP] 35..48 mm).
std::vector<std::pair<std::string, double>> expectedMidline(double dermaMm, double epiduralMm, double bmi = 0)
{
    double skin = 2.0, fat = dermaMm - 2.0, supra = 3.0, inter = 15.0, flavum = 7.4;
    if (bmi > 0) { // physics.md §3.3: SED = 2.52 + 0.11·BMI cm, layers above the epidural space in proportion
        const double s = 10.0 * (2.52 + 0.11 * bmi) / (skin + fat + supra + inter + flavum);
        for (double* t : {&skin, &fat, &supra, &inter, &flavum}) *t *= s;
    }
    return {{"skin", skin}, {"fat", fat}, {"supraspinous_ligament", supra}, {"interspinous_ligament", inter},
        {"ligamentum_flavum", flavum}, {"epidural_space", epiduralMm}, {"dura", 1.0}, {"csf", 13.0}, {"dura", 1.0}};
}

/// Walk down the column through (x, z) from 1 mm above the skin; the boundaries
/// (air -> skin first) must match @p expected within @p tolerance.
void expectMidline(
    const Volume& v, const std::vector<std::pair<std::string, double>>& expected, double tolerance, double x, double z)
{
    constexpr double kAbove = 1.0;
    const auto found = voxelBoundaries(v, Vec3d(x, kAbove, z), Vec3d(0, -1, 0), 120.0);
    ASSERT_GE(found.size(), expected.size());
    double depth = 0.0;
    for (std::size_t n = 0; n < expected.size(); ++n) {
        EXPECT_EQ(found[n].below, expected[n].first) << "boundary " << n;
        EXPECT_NEAR(found[n].depth - kAbove, depth, tolerance) << "top of " << expected[n].first;
        depth += expected[n].second;
    }
}

struct PresetCase {
    LumbarPreset preset;
    double derma, epidural; // [S19] Table I: derma length (mm), epidural space length (mm)
};
const PresetCase kPresetCases[] = {
    {LumbarPreset::Average, 10.0, 6.0},
    {LumbarPreset::Overweight, 30.0, 4.0},
    {LumbarPreset::Calcified, 10.0, 4.0},
};

TEST(LumbarPhantom, MidlineLayersMatchEveryPresetWithinHalfAVoxel)
{
    for (const auto& c : kPresetCases) {
        LumbarParams p;
        p.preset = c.preset;
        const Volume v = makePhantom(lumbarModel(p, table()), p.grid, table());
        SCOPED_TRACE(lumbarPresetName(c.preset));
        // The column of voxel centres nearest the midline: x = z = h/2 (the lattice has faces at 0).
        expectMidline(v, expectedMidline(c.derma, c.epidural), halfVoxel(0.5), 0.25, 0.25);
    }
}

TEST(LumbarPhantom, BmiScalesTheLayersAboveTheEpiduralSpace)
{
    // physics.md §3.3 table: BMI 20, 25, 30, 40 -> SED 47.2, 52.7, 58.2, 69.2 mm.
    const std::map<double, double> sed{{20.0, 47.2}, {25.0, 52.7}, {30.0, 58.2}, {40.0, 69.2}};
    for (const auto& [bmi, sedMm] : sed) {
        for (const auto& c : {kPresetCases[0], kPresetCases[1]}) {
            LumbarParams p;
            p.preset = c.preset;
            p.bmi = bmi;
            SCOPED_TRACE("BMI " + std::to_string(bmi) + " " + lumbarPresetName(c.preset));
            EXPECT_NEAR(lumbarLayout(p, table()).sed(), sedMm, 1e-9);
            const Volume v = makePhantom(lumbarModel(p, table()), p.grid, table());
            expectMidline(v, expectedMidline(c.derma, c.epidural, bmi), halfVoxel(0.5), 0.25, 0.25);
        }
    }
    LumbarParams bad;
    bad.bmi = 5.0;
    EXPECT_THROW(lumbarLayout(bad, table()), ValueError);
}

TEST(LumbarPhantom, AnisotropicAndRotatedGridsKeepTheLayers)
{
    LumbarParams p;
    p.grid.spacing = Vec3d(0.6, 0.35, 0.8);
    p.grid.direction = Eigen::AngleAxisd(0.35, Vec3d(1, 1, 0).normalized()).toRotationMatrix();
    const Volume v = makePhantom(lumbarModel(p, table()), p.grid, table());
    // A sampled point lies in its nearest voxel, whose centre is at most half the
    // voxel diagonal away: boundaries move by at most that much.
    const double tol = 0.5 * p.grid.spacing.norm();
    expectMidline(v, expectedMidline(10.0, 6.0), tol, 0.05, 0.05);
}

TEST(LumbarPhantom, VertebraeAreWhereTheDesignPutsThem)
{
    const LumbarParams p;
    const Volume v = makePhantom(lumbarModel(p, table()), p.grid, table());
    // Midline path ends on the vertebral body after the anterior dura and epidural space:
    // 10 + 18 + 7.4 + 6 + 1 + 13 + 1 + 1 = 57.4 mm.
    EXPECT_EQ(labelAt(v, Vec3d(0.25, -57.6, 0.25)), "cortical_bone");
    EXPECT_EQ(labelAt(v, Vec3d(0.25, -70.1, 0.25)), "cancellous_bone");
    // Spinous processes beside the path (12 mm gap): bone above and below the interspinous ligament.
    EXPECT_EQ(labelAt(v, Vec3d(0.25, -20.1, 10.25)), "cancellous_bone");
    EXPECT_EQ(labelAt(v, Vec3d(0.25, -20.1, -10.25)), "cancellous_bone");
    EXPECT_EQ(labelAt(v, Vec3d(0.25, -20.1, 0.25)), "interspinous_ligament");
    // Laminae beside the flavum (which ends at 35.4 mm): cortical on the canal side.
    EXPECT_EQ(labelAt(v, Vec3d(10.25, -34.6, 20.25)), "cortical_bone");
    EXPECT_EQ(labelAt(v, Vec3d(10.25, -31.1, 20.25)), "cancellous_bone");
}

TEST(LumbarPhantom, GridsAreConsistentAndAirIsInactive)
{
    const LumbarParams p;
    const Volume v = makePhantom(lumbarModel(p, table()), p.grid, table());
    const auto label = labelGrid(v);
    const auto hu = huGrid(v);
    const auto t1 = t1Grid(v);
    ASSERT_TRUE(label && hu && t1);
    EXPECT_EQ(label->activeVoxelCount(), hu->activeVoxelCount());
    EXPECT_EQ(label->activeVoxelCount(), t1->activeVoxelCount());

    auto huAcc = hu->getConstAccessor();
    auto t1Acc = t1->getConstAccessor();
    std::int64_t checked = 0;
    for (auto it = label->cbeginValueOn(); it; ++it) {
        const Tissue& t = table().at(*it);
        ASSERT_NE(t.id, 0) << "air must be inactive";
        const openvdb::Coord c = it.getCoord(); // equal counts plus this: the same active set
        ASSERT_TRUE(huAcc.isValueOn(c) && t1Acc.isValueOn(c)) << t.name;
        ASSERT_EQ(huAcc.getValue(c), float(t.huTypical)) << t.name;
        ASSERT_EQ(t1Acc.getValue(c), float(t.t1(FieldStrength::T1_5))) << t.name;
        ++checked;
    }
    EXPECT_GT(checked, 0);

    // Everything under the skin is tissue, everything above it air: the active
    // voxels are exactly the dense box less the rows whose centres lie at y > 0.
    const IndexBox box = v.indexBox();
    const Vec3i d = box.dims();
    const std::int64_t airRows = box.max.y() + 1; // centres at y = (j + 1/2)·h for j = 0..max
    const std::int64_t expectedActive = box.voxelCount() - airRows * d.x() * d.z();
    EXPECT_EQ(label->activeVoxelCount(), std::uint64_t(expectedActive));
    const double fraction = double(label->activeVoxelCount()) / double(box.voxelCount());
    EXPECT_GT(fraction, 0.90); // 5 mm of air over a ~97 mm deep block
    EXPECT_LT(fraction, 0.97);
    EXPECT_FALSE(label->getConstAccessor().isValueOn(openvdb::Coord(0, airRows - 1, 0)));
    EXPECT_FALSE(hu->getConstAccessor().isValueOn(openvdb::Coord(0, airRows - 1, 0)));
    EXPECT_EQ(hu->getConstAccessor().getValue(openvdb::Coord(0, airRows - 1, 0)), kAirHu);
}

TEST(LumbarPhantom, FieldStrengthSelectsTheT1Column)
{
    LumbarParams p;
    p.grid.field = FieldStrength::T3;
    p.grid.spacing = Vec3d::Constant(1.0);
    const Volume v = makePhantom(lumbarModel(p, table()), p.grid, table());
    // Fat at 3 T: 382 ms (physics.md §5.1); depth 5 mm on the midline is fat.
    const Vec3d ijk = v.worldToIndex(Vec3d(0.5, -5.0, 0.5));
    const openvdb::Coord c(int(std::lround(ijk.x())), int(std::lround(ijk.y())), int(std::lround(ijk.z())));
    EXPECT_EQ(t1Grid(v)->getConstAccessor().getValue(c), 382.0f);
}

TEST(LumbarPhantom, MetadataLayerTableMatchesPhysics)
{
    LumbarParams p;
    p.preset = LumbarPreset::Overweight;
    p.grid.spacing = Vec3d::Constant(2.0); // the layer table is analytic: spacing does not matter
    const Volume v = makePhantom(lumbarModel(p, table()), p.grid, table());
    const auto layers = phantomLayers(v);
    ASSERT_TRUE(layers);
    const auto expected = expectedMidline(30.0, 4.0);
    ASSERT_GE(layers->layers.size(), expected.size());
    double depth = 0.0;
    for (std::size_t n = 0; n < expected.size(); ++n) {
        EXPECT_EQ(layers->layers[n].name, expected[n].first);
        EXPECT_NEAR(layers->layers[n].startMm, depth, 1e-6); // bisection to 1e-9 mm
        depth += expected[n].second;
        EXPECT_NEAR(layers->layers[n].endMm, depth, 1e-6);
    }
}

/// Voxel count per tissue name.
std::map<std::string, std::int64_t> census(const Volume& v)
{
    std::map<std::string, std::int64_t> n;
    for (auto it = labelGrid(v)->cbeginValueOn(); it; ++it) n[table().at(*it).name] += std::int64_t(it.getVoxelCount());
    return n;
}

TEST(SlabPhantom, BoundariesOnVoxelFacesGiveExactCounts)
{
    // physics.md §7 R1: boundaries on voxel faces. Thicknesses are multiples of the
    // y spacing, so every voxel lies wholly inside one layer.
    SlabParams p;
    p.layers = {{"skin", 2.0}, {"fat", 8.0}, {"muscle", 20.0}};
    p.grid.spacing = Vec3d(0.5, 0.4, 0.7);
    const Volume v = makePhantom(slabModel(p, table()), p.grid, table());
    const Vec3i d = v.indexBox().dims();
    const std::int64_t columns = std::int64_t(d.x()) * d.z();
    const auto n = census(v);
    EXPECT_EQ(n.at("skin"), columns * 5);    // 2 mm / 0.4 mm
    EXPECT_EQ(n.at("fat"), columns * 20);    // 8 mm / 0.4 mm
    EXPECT_EQ(n.at("muscle"), columns * 50); // 20 mm / 0.4 mm
    EXPECT_EQ(n.size(), 3u);
}

TEST(SlabPhantom, TiltedLayersWithinHalfAVoxelDiagonal)
{
    SlabParams p;
    p.tiltDeg = 30.0;
    p.grid.spacing = Vec3d::Constant(0.5);
    const Volume v = makePhantom(slabModel(p, table()), p.grid, table());
    const double t = degToRad(30.0);
    const Vec3d inward(0.0, -std::cos(t), -std::sin(t));
    const auto found = voxelBoundaries(v, Vec3d(0.1, 0.0, 0.1) - 0.5 * inward, inward, 30.0);
    ASSERT_EQ(found.size(), 3u);
    const double tol = 0.5 * p.grid.spacing.norm();
    EXPECT_EQ(found[0].below, "skin");
    EXPECT_NEAR(found[0].depth - 0.5, 0.0, tol);
    EXPECT_NEAR(found[1].depth - 0.5, 2.0, tol);
    EXPECT_NEAR(found[2].depth - 0.5, 10.0, tol);
}

TEST(SpherePhantom, ChordAlongTheReferenceColumn)
{
    // physics.md §7 R5: a line at offset rho meets the sphere over 2·sqrt(R² - rho²).
    SphereParams p; // 40 mm of fat, muscle sphere r = 10 mm at depth 20 mm
    const Volume v = makePhantom(sphereModel(p, table()), p.grid, table());
    const double rho = std::sqrt(2.0) * 0.25; // the voxel-centre column x = z = h/2
    const double half = std::sqrt(100.0 - rho * rho);
    const auto found = voxelBoundaries(v, Vec3d(0.25, 0.0, 0.25), Vec3d(0, -1, 0), 40.5);
    ASSERT_GE(found.size(), 3u);
    EXPECT_EQ(found[0].below, "muscle");
    EXPECT_NEAR(found[0].depth, 20.0 - half, halfVoxel(0.5));
    EXPECT_EQ(found[1].below, "fat");
    EXPECT_NEAR(found[1].depth, 20.0 + half, halfVoxel(0.5));
    // Voxel count of the sphere approaches 4/3·pi·R³/h³ (surface error O(R²h)): within 3 %.
    const double exact = 4.0 / 3.0 * kPi * 1000.0 / 0.125;
    EXPECT_NEAR(double(census(v).at("muscle")), exact, 0.03 * exact);
}

TEST(TorsoPhantom, OrgansOfTheSpineBiopsySimulator)
{
    TorsoParams p;
    p.grid.spacing = Vec3d::Constant(2.0);
    const PhantomModel model = torsoModel(p, table());
    const Volume v = makePhantom(model, p.grid, table());
    const auto n = census(v);
    for (const char* organ : {"skin", "fat", "muscle", "cortical_bone", "cancellous_bone", "lesion", "lung", "kidney",
             "aorta", "csf", "spinal_cord"}) {
        EXPECT_GT(n.count(organ) ? n.at(organ) : 0, 0) << organ;
    }
    std::map<std::string, Vec3d> marks(model.landmarks.begin(), model.landmarks.end());
    EXPECT_EQ(labelAt(v, marks.at("lesion")), "lesion");
    EXPECT_EQ(labelAt(v, marks.at("kidney_left")), "kidney");
    EXPECT_EQ(labelAt(v, marks.at("kidney_right")), "kidney");
    EXPECT_EQ(labelAt(v, marks.at("aorta")), "aorta");
    // The aorta lies left of the midline: +x in LPS.
    EXPECT_GT(marks.at("aorta").x(), 0.0);

    // The lesion is inside the vertebral body: every lesion voxel's neighbours are lesion or bone.
    const auto label = labelGrid(v);
    auto acc = label->getConstAccessor();
    const int lesion = table().at("lesion").id;
    const std::set<int> allowed{lesion, table().at("cancellous_bone").id, table().at("cortical_bone").id};
    for (auto it = label->cbeginValueOn(); it; ++it) {
        if (*it != lesion) continue;
        for (const auto& off : {openvdb::Coord(1, 0, 0), openvdb::Coord(-1, 0, 0), openvdb::Coord(0, 1, 0),
                 openvdb::Coord(0, -1, 0), openvdb::Coord(0, 0, 1), openvdb::Coord(0, 0, -1)}) {
            EXPECT_TRUE(allowed.count(acc.getValue(it.getCoord() + off)));
        }
    }
    // Lung bases only in the upper part (z > 30 mm), kidneys below it.
    const int lung = table().at("lung").id, kidney = table().at("kidney").id;
    for (auto it = label->cbeginValueOn(); it; ++it) {
        const Vec3d w = v.indexToWorld(Vec3d(it.getCoord().x(), it.getCoord().y(), it.getCoord().z()));
        if (*it == lung) {
            EXPECT_GT(w.z(), 30.0);
        } else if (*it == kidney) {
            EXPECT_LT(w.z(), 25.0);
        }
    }

    // The reference path goes skin -> ... -> lesion and touches no critical structure.
    const auto layers = phantomLayers(v);
    ASSERT_TRUE(layers);
    EXPECT_EQ(layers->layers.front().name, "skin");
    EXPECT_EQ(layers->layers.back().name, "lesion");
    for (const auto& l : layers->layers) EXPECT_FALSE(table().at(l.name).critical) << l.name;
}

TEST(Phantoms, RejectBadParameters)
{
    SlabParams slab;
    slab.layers = {{"skin", -1.0}};
    EXPECT_THROW(slabModel(slab, table()), ValueError);
    slab.layers = {{"no_such_tissue", 1.0}};
    EXPECT_THROW(slabModel(slab, table()), ValueError);
    slab.layers = {{"air", 1.0}};
    EXPECT_THROW(slabModel(slab, table()), ValueError);
    SphereParams sphere;
    sphere.radiusMm = 30.0; // does not fit in 40 mm
    EXPECT_THROW(sphereModel(sphere, table()), ValueError);
    EXPECT_THROW(parseLumbarPreset("slim"), ValueError);
    GridSpec grid;
    grid.spacing = Vec3d(0.5, 0.0, 0.5);
    EXPECT_THROW(makePhantom(slabModel(SlabParams{}, table()), grid, table()), ValueError);
}

// phantomModel is the one switch from a kind's name to its model (the phantom
// command, scenes and regression suites all call it): each kind reads its own
// parameters, and a kind it does not know is refused naming it.
TEST(PhantomSpecs, EachKindReadsItsOwnParametersAndAnUnknownOneIsRefused)
{
    PhantomSpec spec;
    spec.sphere.radiusMm = 7.0;
    spec.slab.tiltDeg = 20.0;
    spec.lumbar.preset = LumbarPreset::Overweight;
    spec.torso.lesionRadiusMm = 5.0;
    SphereParams sphere;
    sphere.radiusMm = 7.0;
    SlabParams slab;
    slab.tiltDeg = 20.0;
    LumbarParams lumbar;
    lumbar.preset = LumbarPreset::Overweight;
    TorsoParams torso;
    torso.lesionRadiusMm = 5.0;
    const std::pair<const char*, PhantomModel> direct[] = {{"slab", slabModel(slab, table())},
        {"sphere", sphereModel(sphere, table())}, {"lumbar", lumbarModel(lumbar, table())},
        {"torso", torsoModel(torso, table())}};
    for (const auto& [kind, model] : direct) {
        spec.kind = kind;
        const PhantomModel m = phantomModel(spec, table());
        EXPECT_EQ(m.description, model.description) << kind; // the description lists the parameters
        EXPECT_EQ(m.pathTarget, model.pathTarget) << kind;
    }
    spec.kind = "cube";
    try {
        (void)phantomModel(spec, table());
        ADD_FAILURE() << "an unknown kind was accepted";
    } catch (const ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("unknown kind 'cube'"), std::string::npos) << e.what();
    }
}

} // namespace
} // namespace voxhap::volume
