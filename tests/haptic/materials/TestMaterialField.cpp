// SPDX-License-Identifier: Apache-2.0
/// @file TestMaterialField.cpp
/// @brief The mapping layer against physics.md §1.3, §5.3 and §5.4.

#include "common/BuiltinTable.h"
#include "common/TempDirTest.h"
#include "common/Tolerances.h"

#include "core/Errors.h"
#include "haptic/materials/FieldGrids.h"
#include "haptic/materials/MaterialField.h"
#include "phantoms/Phantoms.h"
#include "volume/VolumeFile.h"

#include <cmath>
#include <fstream>

namespace voxhap::haptic {
namespace {

using volume::FieldStrength;

/// C1 and C2 are printed to four significant digits in physics.md §5.4; the fitted
/// β they reproduce is off by up to 856 ms·0.0005e-3/ms + 0.5/2058 ≈ 7e-4 relative.
constexpr double kFitRounding = 1e-3;

using voxhap::test::table;

/// Eq. 4 at 1.5 T with the §5.4 constants, written out here: β = C1·exp(C2·T1),
/// C1 = 2464 N·s/m² = 2464e-6 N·s/mm², C2 = 1.398e-3 ms⁻¹ (physics.md §5.4 table).
double beta15T(double t1Ms) { return 2464e-6 * std::exp(1.398e-3 * t1Ms); }
/// The same at 3 T: C1 = 2058 N·s/m², C2 = 1.533e-3 ms⁻¹ (physics.md §5.4 table).
double beta3T(double t1Ms) { return 2058e-6 * std::exp(1.533e-3 * t1Ms); }

/// The β grid holds floats: 2⁻²⁴ ≈ 6e-8 relative of values up to 1.7e-2 N·s/mm²
/// (the interspinous β) is at most 1e-9 N·s/mm².
constexpr double kFloatGridNsPerMm2 = 1e-9;

TEST(T1DampingLaw, ReproducesTheFittedFatAndMuscleValues)
{
    for (FieldStrength f : {FieldStrength::T1_5, FieldStrength::T3}) {
        const T1DampingLaw law = t1DampingLaw(f);
        const double fatT1 = f == FieldStrength::T3 ? 382.0 : 290.0; // §5.1
        const double muscleT1 = f == FieldStrength::T3 ? 898.0 : 856.0;
        // §5.4: beta_fat = 3696, beta_muscle = 8152 N·s/m² = 3696e-6, 8152e-6 N·s/mm².
        EXPECT_NEAR(law.dampingNsPerMm2(fatT1), 3696e-6, kFitRounding * 3696e-6);
        EXPECT_NEAR(law.dampingNsPerMm2(muscleT1), 8152e-6, kFitRounding * 8152e-6);
        // Ratio 4.354/1.974 = 2.206, the [C-ui] puncture-force ratio the fit targets; the
        // ratio of two values each off by kFitRounding is off by at most twice that.
        EXPECT_NEAR(
            law.dampingNsPerMm2(muscleT1) / law.dampingNsPerMm2(fatT1), 4.354 / 1.974, 2.0 * kFitRounding * 2.206);
    }
}

TEST(T1DampingLaw, ClampsBeforeTheExponential)
{
    const T1DampingLaw law = t1DampingLaw(FieldStrength::T1_5);
    // T1 = 65535 would give exp(91.6) ≈ 6e39 (§5.4): clamped to the muscle value instead.
    EXPECT_EQ(law.dampingNsPerMm2(65535.0), law.dampingNsPerMm2(856.0));
    EXPECT_EQ(law.dampingNsPerMm2(-5.0), law.dampingNsPerMm2(290.0));
    EXPECT_EQ(law.dampingNsPerMm2(std::nan("")), law.dampingNsPerMm2(290.0));
    EXPECT_TRUE(std::isfinite(law.dampingNsPerMm2(std::numeric_limits<double>::infinity())));
}

TEST(ModulusLaws, MatchThePhysicsExamples)
{
    // §1.3: HU 125 -> 0.125 g/cm³ -> E ≈ 369 MPa (Kopperdahl 2002: -34.7 + 3230·0.125 = 369.05).
    const double e = youngsModulusMPa(ModulusLaw::Kopperdahl2002, densityFromHu(125.0));
    EXPECT_NEAR(e, 369.05, 1e-9);
    // §1.3: 18 G tip (1.27 mm²), L_c = 1 mm -> k ≈ 4.7e5 N/m = 470 N/mm (two digits in the text).
    EXPECT_NEAR(contactStiffnessNPerMm(e, 1.27, 1.0), 470.0, 5.0);
    // §5.3: rho_app = 0.2 -> 384 MPa (Morgan); rho_ash ≈ 0.12 -> 32 MPa (Keller), three and two digits.
    EXPECT_NEAR(youngsModulusMPa(ModulusLaw::Morgan2003, 0.2), 384.0, 0.5);
    EXPECT_NEAR(youngsModulusMPa(ModulusLaw::Keller1994, 0.6 * 0.2), 32.0, 0.5);
    // Linear laws never go negative below their intercept; bad input gives 0.
    EXPECT_EQ(youngsModulusMPa(ModulusLaw::Keaveny1997, 0.01), 0.0);
    EXPECT_EQ(youngsModulusMPa(ModulusLaw::Morgan2003, std::nan("")), 0.0);
    EXPECT_EQ(densityFromHu(-500.0), 0.0);
    EXPECT_EQ(parseModulusLaw("morgan2003"), ModulusLaw::Morgan2003);
    EXPECT_THROW(parseModulusLaw("hooke"), ValueError);
}

/// The value of a grid at a world point (its nearest voxel).
template <typename GridT> double at(const GridT& g, const Vec3d& world)
{
    const auto ijk = g.transform().worldToIndex(volume::toVdb(world));
    return double(g.getConstAccessor().getValue(openvdb::Coord::round(ijk)));
}

class LumbarField : public testing::Test {
protected:
    static void SetUpTestSuite()
    {
        volume::LumbarParams p;
        p.grid.spacing = Vec3d::Constant(1.0);
        vol = std::make_unique<volume::Volume>(volume::makePhantom(volume::lumbarModel(p, table()), p.grid, table()));
    }
    static void TearDownTestSuite() { vol.reset(); }
    static inline std::unique_ptr<volume::Volume> vol;
};

TEST_F(LumbarField, DampingFromT1ForFatAndMuscleAndPerLabelOtherwise)
{
    const MaterialField f(*vol, table(), MaterialOptions{});
    const auto beta = detail::dampingGrid(f);
    ASSERT_TRUE(beta);
    // Midline depths (average preset): skin 0-2, fat 2-10, supraspinous 10-13, ... epidural 35.4-41.4.
    // The phantom's t1 grid holds the 1.5 T column of §5.1: fat 290 ms, muscle 856 ms.
    EXPECT_NEAR(at(*beta, {0.5, -5.5, 0.5}), beta15T(290.0), kFloatGridNsPerMm2);   // fat: Eq. 4
    EXPECT_NEAR(at(*beta, {0.5, -1.5, 0.5}), 8152e-6, kFloatGridNsPerMm2);          // skin: table β
    EXPECT_NEAR(at(*beta, {0.5, -20.5, 0.5}), 16304e-6, kFloatGridNsPerMm2);        // interspinous: table β
    EXPECT_NEAR(at(*beta, {30.5, -20.5, 0.5}), beta15T(856.0), kFloatGridNsPerMm2); // paraspinal muscle: Eq. 4
    EXPECT_EQ(at(*beta, {0.5, 2.5, 0.5}), 0.0);                                     // air
    // Air stays inactive: the β grid has exactly the labelled voxels.
    EXPECT_EQ(beta->activeVoxelCount(), volume::labelGrid(*vol)->activeVoxelCount());
    EXPECT_NEAR(f.maxDamping(), 16304e-6, 1e-9);
    EXPECT_EQ(f.perLabel()[std::size_t(table().at("lung").id)].critical, true);
    EXPECT_EQ(f.perLabel()[std::size_t(table().at("cortical_bone").id)].rigid, true);
}

TEST_F(LumbarField, OnlyTheNeededGridsAreBuilt)
{
    MaterialOptions o;
    o.needs.damping = false;
    o.needs.boneStiffness = false;
    const MaterialField none(*vol, table(), o);
    EXPECT_FALSE(none.damping());
    EXPECT_FALSE(none.boneStiffness());
    EXPECT_TRUE(none.labels()); // the labels are the volume's own grid, shared, not rebuilt
    EXPECT_EQ(none.labels().get(), vol->grid(volume::Channel::Label).get());
    o.needs.boneStiffness = true;
    const MaterialField bone(*vol, table(), o);
    EXPECT_FALSE(bone.damping());
    EXPECT_TRUE(bone.boneStiffness());
}

TEST_F(LumbarField, MrIntensityIsNeverReadAsT1)
{
    // The phantom's t1 moved to the intensity channel, labels removed: an MR
    // of some other weighting. Damping needs T1 or labels: refused in one line
    // that names the weighting and the declarations that would make it T1.
    volume::Volume mr(vol->transformPtr()->copy(), vol->indexBox());
    mr.setGrid(volume::Channel::Intensity, vol->grid(volume::Channel::T1)->deepCopyGrid());
    mr.metadata().mrWeighting = voxhap::volume::MrWeightingKind::PdWeighted;
    try {
        const MaterialField f(mr, table(), MaterialOptions{});
        FAIL() << "damping was built from an intensity grid";
    } catch (const ValueError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("PD-weighted"), std::string::npos) << msg;
        EXPECT_NE(msg.find("--t1-weighted"), std::string::npos) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
    // Bone stiffness alone does not read T1, but needs HU: refused too, for its own reason.
    MaterialOptions bone;
    bone.needs.damping = false;
    bone.needs.boneStiffness = true;
    EXPECT_THROW(MaterialField(mr, table(), bone), ValueError);
}

TEST_F(LumbarField, CorruptT1StaysFinite)
{
    volume::Volume copy = *vol;
    auto t1 = openvdb::gridPtrCast<volume::FloatGrid>(vol->grid(volume::Channel::T1)->deepCopyGrid());
    const auto fatVoxel = openvdb::Coord::round(t1->transform().worldToIndex({0.5, -5.5, 0.5}));
    const auto fatVoxel2 = fatVoxel.offsetBy(0, 1, 0);
    t1->tree().setValueOn(fatVoxel, 65535.0f);
    t1->tree().setValueOn(fatVoxel2, std::numeric_limits<float>::quiet_NaN());
    copy.setGrid(volume::Channel::T1, t1);
    const MaterialField f(copy, table(), MaterialOptions{});
    const auto beta = detail::dampingGrid(f);
    // §5.4: T1 is clamped to the fat–muscle range before Eq. 4, so 65535 ms reads as
    // muscle (856 ms at 1.5 T) and NaN as the lower end, fat (290 ms).
    EXPECT_NEAR(beta->getConstAccessor().getValue(fatVoxel), beta15T(856.0), kFloatGridNsPerMm2);
    EXPECT_NEAR(beta->getConstAccessor().getValue(fatVoxel2), beta15T(290.0), kFloatGridNsPerMm2);
    for (auto it = beta->cbeginValueOn(); it; ++it) ASSERT_TRUE(std::isfinite(*it));
}

TEST(MaterialField, BoneStiffnessIsComputedThenLimitedToTheDevice)
{
    volume::TorsoParams p;
    p.grid.spacing = Vec3d::Constant(2.0);
    const volume::Volume v = volume::makePhantom(volume::torsoModel(p, table()), p.grid, table());
    MaterialOptions o;
    o.needs = {false, true};
    o.device = deviceLimits("touch");
    const MaterialField f(v, table(), o);
    const auto& r = f.stiffnessReport();
    // Cortical bone 1850 HU -> 1.85 g/cm³ -> Kopperdahl E = -34.7 + 3230·1.85 MPa; k = E·1.27 mm²/2 mm.
    EXPECT_NEAR(r.computedMaxNPerMm, (-34.7 + 3230.0 * 1.85) * 1.27 / 2.0, 1e-6);
    EXPECT_EQ(r.renderedMaxNPerMm, 0.5); // physics.md §6.3: Touch-class 0.5 N/mm
    std::int64_t bone = 0;
    for (auto it = volume::labelGrid(v)->cbeginValueOn(); it; ++it) {
        if (table().at(*it).rigid) bone += std::int64_t(it.getVoxelCount());
    }
    EXPECT_EQ(r.boneVoxels, bone);
    const auto k = detail::stiffnessGrid(f);
    EXPECT_EQ(std::int64_t(k->activeVoxelCount()), bone);
    for (auto it = k->cbeginValueOn(); it; ++it) ASSERT_LE(*it, 0.5f);
}

/// MR files as a scanner's converter leaves them: a raw NRRD without voxhap's
/// keys and a BIDS sidecar beside it, loaded as a user loads them.
class MrFieldStrength : public voxhap::test::TempDirTest {
protected:
    static constexpr int kN = 32;
    /// A 32³ ball of 10 mm voxels (a 270 mm trunk, so that a T1-weighted image is
    /// normalised): @p shell in the outer 2 voxels (subcutaneous fat), @p core
    /// inside, @p centre within 3 voxels of the centre (fluid), air around it.
    /// Returns the NRRD's path.
    std::filesystem::path write(
        const std::string& name, float shell, float core, float centre, const std::string& sidecar) const
    {
        const std::filesystem::path p = mDir / (name + ".nrrd");
        std::ofstream out(p, std::ios::binary);
        out << "NRRD0004\ntype: float\ndimension: 3\nspace: left-posterior-superior\nsizes: 32 32 32\n"
               "space directions: (10,0,0) (0,10,0) (0,0,10)\nkinds: domain domain domain\nendian: little\n"
               "encoding: raw\nspace origin: (0,0,0)\n\n";
        for (int k = 0; k < kN; ++k)
            for (int j = 0; j < kN; ++j)
                for (int i = 0; i < kN; ++i) {
                    const double r = std::hypot(i - 16.0, j - 16.0, k - 16.0);
                    const float v = r > 13 ? 0.0f : r > 11 ? shell : r < 3 ? centre : core;
                    out.write(reinterpret_cast<const char*>(&v), sizeof v);
                }
        std::ofstream(mDir / (name + ".json")) << sidecar;
        return p;
    }
    /// β in the ball's core and in its shell, no labels: every voxel through Eq. 4.
    static std::pair<double, double> coreAndShellBeta(const volume::Volume& v)
    {
        const MaterialField f(v, table(), MaterialOptions{});
        const auto acc = detail::dampingGrid(f)->getConstAccessor();
        return {acc.getValue({16, 16, 22}), acc.getValue({16, 16, 28})};
    }
    /// A sidecar of an MR at @p tesla: a T1 map, or a T1-weighted spoiled gradient echo.
    static std::string sidecar(double tesla, bool map)
    {
        return R"({"Modality": "MR", "MagneticFieldStrength": )" + std::to_string(tesla) +
            (map ? R"(, "ImageType": ["DERIVED", "PRIMARY", "T1 MAP"]})"
                 : R"(, "ScanningSequence": "GR", "SequenceVariant": ["SP", "OSP"], "SequenceName": "*fl2d1",
                       "RepetitionTime": 0.3, "EchoTime": 0.00246, "FlipAngle": 80, "ImageType": ["ORIGINAL", "PRIMARY", "M"]})");
    }
};

TEST_F(MrFieldStrength, TheDampingLawFollowsTheScansFieldStrength)
{
    // physics.md §5.4: b = C1·exp(C2·T1) with C1, C2 of the scan's field. The
    // two laws differ by 10 % at T1 = 600 ms, far beyond the tolerance: a scan
    // damped with the other field's law fails here (the fault this guards
    // against: every MR loaded from a file got the 1.5 T law).
    ASSERT_GT(std::abs(beta3T(600.0) - beta15T(600.0)), 1e5 * kFloatGridNsPerMm2);
    for (double tesla : {3.0, 1.5, 2.89362}) {
        const volume::Volume map = volume::loadVolume(write("map", 600.0f, 600.0f, 600.0f, sidecar(tesla, true)));
        ASSERT_TRUE(map.has(volume::Channel::T1));
        EXPECT_EQ(map.metadata().t1Kind, volume::T1Kind::Map);
        const double expected = tesla > 2 ? beta3T(600.0) : beta15T(600.0);
        EXPECT_NEAR(coreAndShellBeta(map).first, expected, kFloatGridNsPerMm2) << tesla << " T";
    }
    // A T1-weighted scan normalised per scan at 3 T (§5.1): its fat becomes the
    // table's 382 ms and its muscle 898 ms, and both are damped with the 3 T law,
    // which gives them §5.4's fitted β; the 1.5 T law would give fat 4.21e-3.
    const volume::Volume t1w = volume::loadVolume(write("t1w", 220.0f, 110.0f, 40.0f, sidecar(3.0, false)));
    ASSERT_TRUE(t1w.has(volume::Channel::T1));
    EXPECT_EQ(t1w.metadata().t1Kind, volume::T1Kind::NormalisedWeighted);
    const auto [muscle, fat] = coreAndShellBeta(t1w);
    EXPECT_NEAR(fat, beta3T(382.0), kFloatGridNsPerMm2);
    EXPECT_NEAR(muscle, beta3T(898.0), kFloatGridNsPerMm2);
    EXPECT_NEAR(fat, 3696e-6, kFitRounding * 3696e-6);
}

TEST_F(MrFieldStrength, AFieldWithoutALawIsNotReadAsEither)
{
    // 7 T: no T1 law (physics.md §5.4). A T1-weighted scan is not normalised;
    // a T1 map's T1 is not read, and without labels the damping is refused in
    // one line naming the field and where it came from.
    const volume::Volume t1w = volume::loadVolume(write("t1w", 220.0f, 110.0f, 40.0f, sidecar(7.0, false)));
    EXPECT_FALSE(t1w.has(volume::Channel::T1));
    EXPECT_NE(t1w.metadata().extra.at("t1_norm_refused").find("neither 1.5 T nor 3 T"), std::string::npos);
    volume::Volume map = volume::loadVolume(write("map", 600.0f, 600.0f, 600.0f, sidecar(7.0, true)));
    ASSERT_TRUE(map.has(volume::Channel::T1));
    EXPECT_EQ(map.metadata().fieldStrength, std::nullopt);
    EXPECT_EQ(map.metadata().fieldStrengthTesla, 7.0);
    try {
        const MaterialField f(map, table(), MaterialOptions{});
        FAIL() << "a 7 T T1 map was damped with a 1.5 T or 3 T law";
    } catch (const ValueError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("7 T, from the sidecar"), std::string::npos) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
    // With labels, fat takes the table's β like every other tissue, not Eq. 4.
    const int fat = table().at("fat").id;
    auto labels = volume::LabelGrid::create(volume::kAirLabel);
    labels->setTransform(map.transformPtr()->copy());
    labels->tree().setValueOn(openvdb::Coord(16, 16, 16), fat);
    map.setGrid(volume::Channel::Label, labels);
    const MaterialField f(map, table(), MaterialOptions{});
    EXPECT_NEAR(detail::dampingGrid(f)->getConstAccessor().getValue({16, 16, 16}), 3696e-6, kFloatGridNsPerMm2);
    // The caller's own field overrides the metadata (MaterialOptions::field).
    map.removeGrid(volume::Channel::Label);
    MaterialOptions at3T;
    at3T.field = volume::FieldStrength::T3;
    const MaterialField chosen(map, table(), at3T);
    EXPECT_NEAR(
        detail::dampingGrid(chosen)->getConstAccessor().getValue({16, 16, 22}), beta3T(600.0), kFloatGridNsPerMm2);
}

TEST(MaterialField, RejectsLabelsBeyondTheForcePathRange)
{
    volume::initializeOpenVdb();
    auto labels = volume::LabelGrid::create(0);
    labels->tree().setValueOn(openvdb::Coord(0, 0, 0), 100);
    EXPECT_THROW(MaterialField(nullptr, labels, table()), ValueError);
}

} // namespace
} // namespace voxhap::haptic
