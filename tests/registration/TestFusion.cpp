// SPDX-License-Identifier: Apache-2.0
/// @file TestFusion.cpp
/// @brief The fusion's refusals and self-report, each with the case that passes
/// beside it, and the fused volume's channels and record.

#include "common/TempDirTest.h"
#include "core/Errors.h"
#include "phantoms/PhantomScans.h"
#include "registration/Fusion.h"
#include "registration/LevelImage.h"
#include "registration/RegistrationFixtures.h"
#include "registration/TransformFile.h"
#include "registration/detail/SurfaceCheck.h"
#include "volume/Grids.h"
#include "volume/VolumeFile.h"

#include <gtest/gtest.h>

namespace voxhap::registration {
namespace {

using volume::Channel;

/// The lumbar phantom's CT and its MR moved by @p shift (fast: a 80 mm block).
struct Pair {
    volume::Volume ct, mr;
    volume::PhantomScanTruth truth;
};

Pair lumbarPair(const std::filesystem::path& dir, const Vec3d& shift, const Vec3d& degrees = Vec3d::Zero(),
    volume::FieldStrength field = volume::FieldStrength::T1_5)
{
    const auto& table = volume::TissueTable::builtin();
    volume::PhantomSpec spec;
    spec.kind = "lumbar";
    const volume::PhantomModel model = volume::phantomModel(spec, table);
    volume::GridSpec grid;
    grid.spacing = Vec3d(1.0, 1.0, 1.0);
    volume::PhantomMrScan scan;
    scan.rotation = test::rotationDeg(degrees);
    scan.translationMm = shift;
    scan.field = field;
    volume::PhantomScanTruth truth;
    const volume::Volume scanned = volume::phantomMrScan(model, table, scan, &truth);
    volume::writePhantomMrScan(scanned, scan.field, dir / "mr.nrrd");
    return {volume::phantomCtScan(model, grid, table), volume::loadVolume(dir / "mr.nrrd"), truth};
}

class Fusion : public test::TempDirTest { };

TEST_F(Fusion, RefusesTooLittleOverlapFromTheGeometryButNotFromTheSearch)
{
    const Pair p = lumbarPair(mDir, Vec3d(0, 0, 400)); // the MR's body 400 mm away, beyond the CT
    RegistrationOptions geometry;
    geometry.start = StartRule::Geometry;
    try {
        registerMrToCt(p.ct, p.mr, geometry);
        FAIL() << "registered with no overlap";
    } catch (const ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("too little overlap: 0.0 %"), std::string::npos) << e.what();
    }
    // The search brings the bodies' centres together: the same pair registers.
    const RegistrationResult r = registerMrToCt(p.ct, p.mr);
    EXPECT_GT(r.overlapStart, 0.9);
    const Vec3d x(0, -30, 0);
    EXPECT_LT((r.mrFromCt.apply(x) - p.truth.apply(x)).norm(), 1.0);
}

TEST_F(Fusion, TheSurfaceCheckSeesABodyShiftedByTwoVoxelDiagonals)
{
    const Pair p = lumbarPair(mDir, Vec3d(3, -2, 5));
    const LevelImage ct = blockAverage(p.ct, Channel::Hu, Vec3i(1, 1, 1));
    const LevelImage mr = blockAverage(p.mr, Channel::T1, Vec3i(1, 1, 1));
    const AffineMap truth{p.truth.linear, p.truth.offset};
    const detail::SurfaceDistance right = detail::surfaceDistance(ct, mr, truth);
    EXPECT_GT(right.points, 1000);
    // The MR's voxels are 1 × 1 × 4 mm: its surface is found to about half a
    // voxel diagonal where the skin is parallel to the slices.
    EXPECT_LT(right.meanMm, 0.5 * p.mr.geometry().spacing.norm());
    // The skin (the block's only surface inside both fields of view) is normal
    // to y, 80 × 80 mm: shifted along y by twice the limit, its points lie at
    // least the limit from the MR's surface but within the limit of the block's
    // sides (x, z = ±40 mm), a band of under half its area.
    const double limit = 2.0 * p.mr.geometry().spacing.norm();
    const AffineMap shifted{truth.linear, truth.offset + Vec3d(0, 2.0 * limit, 0)};
    EXPECT_GT(detail::surfaceDistance(ct, mr, shifted).meanMm, limit);
}

TEST_F(Fusion, ReportsAFinestStageStoppedAtItsLimitAsNotConverged)
{
    const Pair p = lumbarPair(mDir, Vec3d(4, 6, -3), Vec3d(4, -3, 5));
    RegistrationOptions few;
    few.iterations = 2; // the limit hit while the metric still moves
    const RegistrationResult r = registerMrToCt(p.ct, p.mr, few);
    EXPECT_FALSE(r.converged);
    ASSERT_FALSE(r.warnings.empty());
    EXPECT_NE(r.warnings.front().find("did not converge"), std::string::npos) << r.warnings.front();
    const RegistrationResult full = registerMrToCt(p.ct, p.mr);
    EXPECT_TRUE(full.converged) << full.stopReason;
}

TEST_F(Fusion, RefusesSwappedInputsAndAOneSliceMrNamingTheFile)
{
    const Pair p = lumbarPair(mDir, Vec3d::Zero());
    FusionOptions o;
    o.ctFile = "ct.nrrd";
    o.mrFile = "mr.nrrd";
    auto refusal = [&](const volume::Volume& ct, const volume::Volume& mr) -> std::string {
        try {
            checkFusionInputs(ct, mr, o);
        } catch (const ValueError& e) {
            return e.what();
        }
        return "";
    };
    EXPECT_EQ(refusal(p.ct, p.mr), "");
    EXPECT_EQ(
        refusal(p.mr, p.ct), "ct.nrrd: this is the MR and mr.nrrd is the CT: give the CT first (voxhap fuse CT MR)");
    EXPECT_NE(refusal(p.ct, p.ct).find("mr.nrrd: given as the MR, but it is a CT"), std::string::npos);
    EXPECT_NE(refusal(p.mr, p.mr).find("ct.nrrd: given as the CT, but it is an MR"), std::string::npos);
    // One slice of the MR.
    volume::IndexBox slab = p.mr.indexBox();
    slab.max.z() = slab.min.z();
    volume::Volume thin(p.mr.transformPtr()->copy(), slab);
    thin.setGrid(Channel::T1, std::const_pointer_cast<openvdb::GridBase>(p.mr.grid(Channel::T1)));
    EXPECT_NE(refusal(p.ct, thin).find("mr.nrrd: the MR is"), std::string::npos);
    EXPECT_NE(refusal(p.ct, thin).find("one slice cannot be registered in 3D"), std::string::npos);
}

TEST(FusionPatients, DifferentIdsOrNamesAreRefusedWhenBothSayThem)
{
    FusionOptions o;
    o.ctFile = "ct/";
    o.mrFile = "mr/";
    EXPECT_NO_THROW(checkSamePatient({"P1", "DOE^JANE"}, {"P1", "Doe^Jane^^"}, o)); // case and empty components
    EXPECT_NO_THROW(checkSamePatient({"", "DOE^JANE"}, {"P2", ""}, o));             // nothing both say differs
    EXPECT_THROW(checkSamePatient({"P1", ""}, {"P2", ""}, o), ValueError);
    EXPECT_THROW(checkSamePatient({"", "DOE^JANE"}, {"", "ROE^JOHN"}, o), ValueError);
    try {
        checkSamePatient({"P1", ""}, {"P2", ""}, o);
    } catch (const ValueError& e) {
        EXPECT_EQ(std::string(e.what()),
            "mr/: PatientID 'P2' differs from ct/'s 'P1': these may be two patients (--different-patients fuses them "
            "anyway)");
    }
}

TEST_F(Fusion, TheFusedVolumeHoldsTheCtAndTheRegisteredMrOnTheCtGrid)
{
    const Pair p = lumbarPair(mDir, Vec3d(-6, 4, 9), Vec3d(0, 0, 8));
    FusionOptions o;
    o.ctFile = "ct";
    o.mrFile = "mr.nrrd";
    const FusionResult f = fuse(p.ct, p.mr, o);
    const volume::Volume& v = f.volume;
    EXPECT_EQ(v.indexBox(), p.ct.indexBox());
    EXPECT_TRUE(v.transform() == p.ct.transform());
    ASSERT_TRUE(v.has(Channel::Hu));
    ASSERT_TRUE(v.has(Channel::T1));
    EXPECT_EQ(volume::huGrid(v)->activeVoxelCount(), volume::huGrid(p.ct)->activeVoxelCount());
    EXPECT_GT(f.resample.activeVoxels, 0);
    ASSERT_TRUE(v.metadata().fusion);
    const volume::FusionRecord& rec = *v.metadata().fusion;
    EXPECT_LT((rec.mrFromCt - f.registration.mrFromCt.matrix()).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((parseItkTransform(rec.itkTransform, "record").matrix() - rec.mrFromCt).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_EQ(rec.channelSources.count("hu"), 1u);
    EXPECT_EQ(rec.channelSources.count("t1"), 1u);
    // The fused T1 of the muscle below the vertebral body is muscle's T1 (the
    // noise averages out over the region; σ is 5 % of muscle T1 per voxel).
    const auto& table = volume::TissueTable::builtin();
    auto acc = volume::t1Grid(v)->getConstAccessor();
    auto huAcc = volume::huGrid(v)->getConstAccessor();
    const Vec3d probe = v.worldToIndex(Vec3d(30.0, -50.0, 0.0));
    ASSERT_EQ(huAcc.getValue(openvdb::Coord(
                  int(std::lround(probe.x())), int(std::lround(probe.y())), int(std::lround(probe.z())))),
        float(table.at("muscle").huTypical))
        << "the region is muscle";
    double sum = 0;
    int n = 0;
    for (int i = -10; i <= 10; ++i) {
        for (int k = -10; k <= 10; ++k) {
            const Vec3d ijk = v.worldToIndex(Vec3d(30.0 + 0.2 * i, -50.0, 0.5 * k)); // lateral muscle
            float value = 0;
            if (acc.probeValue(
                    openvdb::Coord(int(std::lround(ijk.x())), int(std::lround(ijk.y())), int(std::lround(ijk.z()))),
                    value)) {
                sum += value;
                ++n;
            }
        }
    }
    ASSERT_GT(n, 100);
    EXPECT_NEAR(sum / n, table.at("muscle").t1(volume::FieldStrength::T1_5),
        0.02 * table.at("muscle").t1(volume::FieldStrength::T1_5));
    // Saved and loaded, the record comes back whole.
    volume::saveVolume(v, mDir / "fused.vdb");
    const volume::Volume back = volume::loadVolume(mDir / "fused.vdb");
    ASSERT_TRUE(back.metadata().fusion);
    EXPECT_EQ(*back.metadata().fusion, rec);
}

} // namespace
} // namespace voxhap::registration

namespace voxhap::registration {
namespace {

class RegistrationRepeat : public test::TempDirTest { };

TEST_F(RegistrationRepeat, TheSameInputsGiveTheSameAnswerBitForBit)
{
    // With ITK's metric on two work units the derivative sums were added in
    // the threads' arrival order, and the porcine pair's answer moved by up to
    // a millimetre from one run to the next. Two runs here, with the search's
    // lanes racing each other, must agree exactly.
    const Pair p = lumbarPair(mDir, Vec3d(8, -6, 12), Vec3d(6, -4, 9));
    const RegistrationResult a = registerMrToCt(p.ct, p.mr);
    const RegistrationResult b = registerMrToCt(p.ct, p.mr);
    EXPECT_EQ(a.mrFromCt.matrix(), b.mrFromCt.matrix());
    EXPECT_EQ(a.metricFinal, b.metricFinal);
    EXPECT_EQ(a.iterations, b.iterations);
    ASSERT_EQ(a.candidates.size(), b.candidates.size());
    for (std::size_t i = 0; i < a.candidates.size(); ++i) EXPECT_EQ(a.candidates[i].metric, b.candidates[i].metric);
}

} // namespace
} // namespace voxhap::registration

namespace voxhap::registration {
namespace {

class FusionField : public test::TempDirTest { };

/// The fused volume keeps what the MR's sidecar said of its field, and so
/// takes the damping law of that field (physics.md §5.4): a 3 T MR gives the
/// fused volume 3 T from the sidecar, a 1.5 T one 1.5 T.
TEST_F(FusionField, TheFusedVolumeKeepsTheMrsFieldStrengthAndItsSource)
{
    for (const auto field : {volume::FieldStrength::T3, volume::FieldStrength::T1_5}) {
        const Pair p = lumbarPair(mDir, Vec3d(4, -3, 6), Vec3d::Zero(), field);
        ASSERT_EQ(p.mr.metadata().fieldStrength, field) << "the sidecar says the field";
        FusionOptions o;
        o.ctFile = "ct";
        o.mrFile = "mr.nrrd";
        const FusionResult f = fuse(p.ct, p.mr, o);
        EXPECT_EQ(f.volume.metadata().fieldStrength, field);
        EXPECT_EQ(f.volume.metadata().fieldStrengthSource, volume::FactSource::Sidecar);
        EXPECT_EQ(f.volume.metadata().t1Kind, volume::T1Kind::Map);
    }
}

} // namespace
} // namespace voxhap::registration
