// SPDX-License-Identifier: Apache-2.0
/// @file TestOutsideTorso.cpp
/// @brief Segmentation outside the torso (issue 27 item 11): the width test of
/// TorsoExtent.h, a head-sized CT phantom whose bright structures the torso
/// rules would call aorta and kidney, MR heads whose white matter is as bright
/// as fat, and MR of unknown weighting.

#include "SegmentationFixtures.h"

#include "common/BuiltinTable.h"
#include "segmentation/Segmentation.h"
#include "segmentation/TorsoExtent.h"
#include "volume/Grids.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <numbers>
#include <string>

namespace voxhap::segmentation {
namespace {

using test::table;

// Voxels of the phantoms: 1 mm in-plane, 2 mm slices (a routine head CT or 2D MR).
const Vec3d kSpacing(1.0, 1.0, 2.0);
// Air around the body [mm]: the body must not touch the field of view's edge.
constexpr double kAirMarginMm = 10.0;
// A width is measured from voxel faces; the phantom's surface cuts voxels, so the
// measured width may differ from the drawn one by up to one voxel on each side.
constexpr double kWidthToleranceMm = 2.0;
// CT quantum noise in a head [HU]: brain noise of a routine head CT is 3–5 HU; 10 is generous.
constexpr double kHeadNoiseHu = 10.0;

/// True where @p p lies inside the ellipsoid of semi-axes @p semi shrunk by @p depthMm.
bool within(const Vec3d& p, const Vec3d& semi, double depthMm)
{
    return (p.array() / (semi.array() - depthMm)).square().sum() < 1.0;
}

/// True where @p p lies inside the elliptic cylinder along z of in-plane semi-axes
/// @p semi shrunk by @p depthMm (a trunk segment cut by the scan's ends).
bool withinCylinder(const Vec3d& p, const Vec3d& semi, double depthMm)
{
    return (p.head<2>().array() / (semi.head<2>().array() - depthMm)).square().sum() < 1.0;
}

/// A volume over the ellipsoid of semi-axes @p semi (plus the air margin),
/// centred on the world origin, whose @p channel holds value(p); voxels equal to
/// @p background stay inactive.
volume::Volume raster(
    const Vec3d& semi, volume::Channel channel, float background, const std::function<float(const Vec3d&)>& value)
{
    volume::Geometry g;
    g.spacing = kSpacing;
    const Vec3i half = ((semi.array() + kAirMarginMm) / kSpacing.array()).ceil().cast<int>();
    g.origin = -(half.cast<double>().array() * kSpacing.array()).matrix();
    volume::Volume v(g, volume::IndexBox{Vec3i::Zero(), 2 * half});
    auto grid = volume::FloatGrid::create(background);
    auto acc = grid->getAccessor();
    for (int k = 0; k <= 2 * half.z(); ++k) {
        for (int j = 0; j <= 2 * half.y(); ++j) {
            for (int i = 0; i <= 2 * half.x(); ++i) {
                const float x = value(v.indexToWorld(Vec3d(i, j, k)));
                if (x != background) acc.setValue(openvdb::Coord(i, j, k), x);
            }
        }
    }
    v.setGrid(channel, grid);
    return v;
}

int labelOf(const volume::Volume& v, const Vec3d& w)
{
    const Vec3d ijk = v.worldToIndex(w);
    return volume::labelGrid(v)->getConstAccessor().getValue(
        openvdb::Coord(int(std::lround(ijk.x())), int(std::lround(ijk.y())), int(std::lround(ijk.z()))));
}

std::map<std::string, double> mlByName(const SegmentReport& r)
{
    std::map<std::string, double> out;
    for (const auto& l : r.labels) out[l.name] = l.ml;
    return out;
}

bool hasNote(const SegmentReport& r, const std::string& text)
{
    for (const auto& n : r.notes) {
        if (n.find(text) != std::string::npos) return true;
    }
    return false;
}

// ---------------------------------------------------------------------------
// The width test itself.

TEST(TorsoExtent, WidthIsTheCrossSectionsExtentAcrossThePatient)
{
    // An elliptic cylinder 200 mm across (x) and 150 mm deep (y), with air around it.
    const Vec3d semi(100.0, 75.0, 40.0);
    const volume::Volume v = raster(semi, volume::Channel::Hu, volume::kAirHu, [&](const Vec3d& p) {
        const bool inside = withinCylinder(p, semi, 0.0) && std::abs(p.z()) < semi.z();
        return inside ? 40.0f : volume::kAirHu;
    });
    const Lattice lat = Lattice::of(v);
    const auto hu = volume::huGrid(v);
    Mask body(lat.size(), 0);
    for (auto it = hu->cbeginValueOn(); it; ++it) {
        const openvdb::Coord c = it.getCoord() - openvdb::Coord(lat.origin.x(), lat.origin.y(), lat.origin.z());
        body[lat.index(c.x(), c.y(), c.z())] = 1;
    }
    const TorsoExtent e = torsoExtent(v, lat, body);
    EXPECT_NEAR(e.widestMm(), 200.0, kWidthToleranceMm);
    EXPECT_GT(e.bodySlices, 0);
    EXPECT_FALSE(e.undetermined);
    EXPECT_TRUE(e.none()) << "200 mm is narrower than any adult torso";
    for (std::size_t s = 0; s < e.cut.size(); ++s) EXPECT_EQ(e.cut[s], 0) << "slice " << s;
}

TEST(TorsoExtent, ABodyCutByTheFieldOfViewIsUndetermined)
{
    // A block that fills the lattice left to right (a small-field spine CT, the
    // block phantoms): 100 mm is a lower bound, not a width.
    volume::Geometry g;
    g.spacing = Vec3d(1.0, 1.0, 2.0);
    volume::Volume v(g, volume::IndexBox{Vec3i::Zero(), Vec3i(99, 79, 19)});
    const Lattice lat = Lattice::of(v);
    Mask body(lat.size(), 0);
    for (int k = 0; k < 20; ++k) {
        for (int j = 20; j < 60; ++j) {
            for (int i = 0; i < 100; ++i) body[lat.index(i, j, k)] = 1;
        }
    }
    const TorsoExtent e = torsoExtent(v, lat, body);
    EXPECT_TRUE(e.undetermined);
    EXPECT_TRUE(e.all()) << "undetermined: the torso rules apply as before, with a note";
    EXPECT_EQ(e.cut[0], 1);
    EXPECT_NE(torsoNote(v, lat, e, "rules", "x").find("cannot be told"), std::string::npos);
}

// ---------------------------------------------------------------------------
// A head CT: skin, scalp fat, skull, CSF and brain, plus two contrast-enhanced
// structures built to pass the trunk's shape rules (CtSegmentation.h): a tube
// on the midline 80 mm long and 20 mm across (the aorta rule) and a 51 ml
// blob of 200 HU 45 mm lateral of the skull's centre (the kidney rule). The
// same layers as a trunk segment 300 mm wide are the control: there the torso
// rules apply.

struct HeadLayers {
    double skin = 2.0, fat = 4.0, skull = 6.0, csf = 2.0; ///< thicknesses [mm], outside in
};

constexpr double kTubeRadiusMm = 10.0, kTubeHalfLengthMm = 40.0;
constexpr double kBlobRadiusMm = 23.0, kBlobX = 45.0;

/// @param trunk an elliptic cylinder filling the scan's length instead of an ellipsoid
volume::Volume headCt(double halfWidthMm, bool trunk = false)
{
    const auto& t = table();
    const Vec3d semi(halfWidthMm, 105.0, 60.0);
    const HeadLayers L;
    const auto inLayer = [&](const Vec3d& p, const Vec3d& s, double depthMm) {
        return trunk ? withinCylinder(p, s, depthMm) : within(p, s, depthMm);
    };
    volume::Volume v = raster(semi, volume::Channel::Hu, volume::kAirHu, [&](const Vec3d& p) {
        if (!inLayer(p, semi, 0.0)) return volume::kAirHu;
        double d = L.skin;
        if (!inLayer(p, semi, d)) return float(t.at("skin").huTypical);
        if (!inLayer(p, semi, d += L.fat)) return float(t.at("fat").huTypical);
        if (!inLayer(p, semi, d += L.skull)) return float(t.at("cortical_bone").huTypical);
        if (!inLayer(p, semi, d += L.csf)) return float(t.at("csf").huTypical);
        if (p.head<2>().norm() < kTubeRadiusMm && std::abs(p.z()) < kTubeHalfLengthMm)
            return float(t.at("aorta").huTypical);
        if ((p - Vec3d(kBlobX, 0, 0)).norm() < kBlobRadiusMm) return float(t.at("kidney").huTypical);
        return 35.0f; // brain: grey and white matter 30–40 HU
    });
    auto hu = openvdb::gridPtrCast<volume::FloatGrid>(v.grid(volume::Channel::Hu)->deepCopyGrid());
    test::addNoise(*hu, kHeadNoiseHu, 27);
    v.setGrid(volume::Channel::Hu, hu);
    return v;
}

struct SegmentedHead {
    std::unique_ptr<volume::Volume> v;
    SegmentReport report;
};

const SegmentedHead& head()
{
    static const SegmentedHead s = [] {
        SegmentedHead out;
        out.v = std::make_unique<volume::Volume>(headCt(90.0)); // 180 mm across: an adult head
        out.report = segment(*out.v, table());
        return out;
    }();
    return s;
}

TEST(OutsideTorso, HeadCtHasNoTorsoClassesAndSaysSo)
{
    const SegmentedHead& s = head();
    EXPECT_EQ(s.report.method, "ct");
    EXPECT_NEAR(s.report.bodyWidthMm, 180.0, kWidthToleranceMm);
    EXPECT_EQ(s.report.torsoFraction, 0.0);
    EXPECT_TRUE(hasNote(s.report, "CT torso rules not applied")) << ::testing::PrintToString(s.report.notes);
    const auto ml = mlByName(s.report);
    for (const char* n : {"muscle", "aorta", "kidney", "spinal_cord", "lung"}) EXPECT_EQ(ml.count(n), 0u) << n;
    for (const char* n : {"skin", "fat", "soft_tissue"}) EXPECT_GT(ml.count(n) ? ml.at(n) : 0.0, 0.0) << n;
    EXPECT_GT(ml.count("cortical_bone") ? ml.at("cortical_bone") : 0.0, 0.0);
    EXPECT_TRUE(s.report.distanceFields.empty()) << "no critical structure in a head phantom";
}

TEST(OutsideTorso, HeadCtLabelsEachLayerByWhatItsNumbersSay)
{
    const SegmentedHead& s = head();
    const auto id = [](const char* n) { return table().at(n).id; };
    // On the lateral axis, at the middle of each layer (depths from the phantom's drawing).
    EXPECT_EQ(labelOf(*s.v, Vec3d(90.0 - 4.0, 0, 0)), id("fat"));           // fat 2–6 mm deep
    EXPECT_EQ(labelOf(*s.v, Vec3d(90.0 - 9.0, 0, 0)), id("cortical_bone")); // skull 6–12 mm
    EXPECT_EQ(labelOf(*s.v, Vec3d(-20.0, 60.0, 0)), id("soft_tissue"));     // brain
    EXPECT_EQ(labelOf(*s.v, Vec3d(0, 0, 0)), id("soft_tissue"));            // the tube's axis: no aorta
    EXPECT_EQ(labelOf(*s.v, Vec3d(kBlobX, 0, 0)), id("soft_tissue"));       // the blob's centre: no kidney
    EXPECT_EQ(labelOf(*s.v, Vec3d(0, 0, 60.0 + 5.0)), 0);                   // air above the vertex
}

TEST(OutsideTorso, TheSamePhantomTorsoWideGetsTheTorsoRules)
{
    // Control: the phantom's structures do trip the trunk's rules when the body is
    // as wide as a torso, so the head's result above is the anatomy test's doing.
    volume::Volume v = headCt(150.0, true);
    const SegmentReport r = segment(v, table());
    EXPECT_NEAR(r.bodyWidthMm, 300.0, kWidthToleranceMm);
    EXPECT_EQ(r.torsoFraction, 1.0);
    EXPECT_TRUE(r.notes.empty()) << ::testing::PrintToString(r.notes);
    const auto ml = mlByName(r);
    for (const char* n : {"muscle", "aorta", "kidney"}) EXPECT_GT(ml.count(n) ? ml.at(n) : 0.0, 0.0) << n;
}

// ---------------------------------------------------------------------------
// MR heads: skin, scalp fat, skull (no signal), CSF, grey matter and a white
// matter core as bright as fat. The shared MPRAGE's per-scan normalisation puts
// its white matter at about 380 ms, fat's T1 at 3 T (TestRealMrSegmentation.cpp):
// no intensity threshold can split them; only the depth can.

constexpr double kMrHalfWidthMm = 80.0;
const Vec3d kMrSemi(kMrHalfWidthMm, 95.0, 60.0);
constexpr double kGreyMm = 4.0; // cortex thickness over the white matter [mm]

/// The head's value per tissue: {skin, fat, skull, csf, grey, white}.
volume::Volume mrHead(volume::Channel channel, const std::array<float, 6>& value)
{
    const HeadLayers L;
    return raster(kMrSemi, channel, 0.0f, [&](const Vec3d& p) {
        if (!within(p, kMrSemi, 0.0)) return 0.0f;
        double d = L.skin;
        if (!within(p, kMrSemi, d)) return value[0];
        if (!within(p, kMrSemi, d += L.fat)) return value[1];
        if (!within(p, kMrSemi, d += L.skull)) return value[2];
        if (!within(p, kMrSemi, d += L.csf)) return value[3];
        if (!within(p, kMrSemi, d += kGreyMm)) return value[4];
        return value[5];
    });
}

/// Analytic volume of the scalp's fat layer [ml].
double fatShellMl()
{
    const HeadLayers L;
    const auto ellipsoidMl = [](const Vec3d& s) { return 4.0 / 3.0 * std::numbers::pi * s.prod() * 1e-3; };
    return ellipsoidMl(kMrSemi.array() - L.skin) - ellipsoidMl(kMrSemi.array() - L.skin - L.fat);
}

// The fat found in the scalp against the drawn layer: the skin shell reaches half
// a voxel into the fat (CtSegmentation.h markSkin), and the 2 mm slices cut the
// 4 mm layer obliquely near the vertex: 60–120 % of the drawn volume.
constexpr double kFatShellLow = 0.6, kFatShellHigh = 1.2;

void expectScalpFatOnly(const volume::Volume& v, const SegmentReport& r)
{
    EXPECT_EQ(r.method, "mr");
    EXPECT_NEAR(r.bodyWidthMm, 2 * kMrHalfWidthMm, kWidthToleranceMm);
    EXPECT_TRUE(hasNote(r, "fat | muscle split not applied")) << ::testing::PrintToString(r.notes);
    const auto ml = mlByName(r);
    EXPECT_EQ(ml.count("muscle"), 0u);
    for (const auto& l : r.labels)
        EXPECT_TRUE(l.name == "skin" || l.name == "fat" || l.name == "soft_tissue") << l.name;
    const double fat = ml.count("fat") ? ml.at("fat") : 0.0;
    EXPECT_GT(fat, kFatShellLow * fatShellMl());
    EXPECT_LT(fat, kFatShellHigh * fatShellMl()) << "fat beyond the scalp: white matter taken for fat";
    const auto id = [](const char* n) { return table().at(n).id; };
    EXPECT_EQ(labelOf(v, Vec3d(kMrHalfWidthMm - 4.0, 0, 0)), id("fat")); // the scalp fat's middle
    EXPECT_EQ(labelOf(v, Vec3d(0, 0, 0)), id("soft_tissue"));            // white matter
    EXPECT_EQ(labelOf(v, Vec3d(0, 95.0 - 20.0, 0)), id("soft_tissue"));  // deep in the head, behind
}

TEST(OutsideTorso, MrT1HeadHasScalpFatAndNoMuscle)
{
    // T1 [ms] at 3 T: skin 900, fat 382, muscle-like grey matter 1400, CSF 4000,
    // no signal in the skull (the normalisation's ceiling, 5000 ms), white matter at fat's 382.
    volume::Volume v = mrHead(volume::Channel::T1, {900.0f, 382.0f, 5000.0f, 4000.0f, 1400.0f, 382.0f});
    v.metadata().modality = "MR";
    v.metadata().mrWeighting = voxhap::volume::MrWeightingKind::T1Weighted;
    const SegmentReport r = segment(v, table());
    expectScalpFatOnly(v, r);
}

TEST(OutsideTorso, MrT1WeightedIntensityHeadHasScalpFatAndNoMuscle)
{
    // A T1-weighted series that could not be normalised: an intensity grid, fat bright,
    // white matter as bright, CSF and bone dark (arbitrary units 0–800).
    volume::Volume v = mrHead(volume::Channel::Intensity, {300.0f, 700.0f, 20.0f, 60.0f, 350.0f, 700.0f});
    v.metadata().modality = "MR";
    v.metadata().mrWeighting = voxhap::volume::MrWeightingKind::T1Weighted;
    const SegmentReport r = segment(v, table());
    expectScalpFatOnly(v, r);
}

TEST(OutsideTorso, MrOfUnknownWeightingIsABodyOfSoftTissueWithANote)
{
    // A T2-like contrast (fluid bright, fat middling) that segmentation must not read.
    volume::Volume v = mrHead(volume::Channel::Intensity, {300.0f, 450.0f, 20.0f, 800.0f, 500.0f, 400.0f});
    v.metadata().modality = "MR";
    v.metadata().mrWeighting = voxhap::volume::MrWeightingKind::Unknown;
    const SegmentReport r = segment(v, table());
    EXPECT_EQ(r.method, "mr");
    ASSERT_EQ(r.labels.size(), 1u) << "only soft_tissue";
    EXPECT_EQ(r.labels[0].name, "soft_tissue");
    // The body is the whole ellipsoid: its volume within 3 %, the partial voxels
    // of a 1 × 1 × 2 mm lattice on a surface 160 mm across.
    const double bodyMl = 4.0 / 3.0 * std::numbers::pi * kMrSemi.prod() * 1e-3;
    EXPECT_NEAR(r.labels[0].ml, bodyMl, 0.03 * bodyMl);
    EXPECT_TRUE(hasNote(r, "weighting: unknown")) << ::testing::PrintToString(r.notes);
    EXPECT_TRUE(hasNote(r, "soft_tissue only"));
}

TEST(OutsideTorso, AVolumeWithOnlyAnIntensityGridCanBeSegmented)
{
    volume::Volume v = mrHead(volume::Channel::Intensity, {300.0f, 450.0f, 20.0f, 800.0f, 500.0f, 400.0f});
    v.metadata().mrWeighting = voxhap::volume::MrWeightingKind::PdWeighted;
    ASSERT_FALSE(v.has(volume::Channel::Hu));
    ASSERT_FALSE(v.has(volume::Channel::T1));
    const SegmentReport r = segment(v, table());
    EXPECT_TRUE(v.has(volume::Channel::Label));
    EXPECT_TRUE(hasNote(r, "weighting: PD-weighted")) << ::testing::PrintToString(r.notes);
}

} // namespace
} // namespace voxhap::segmentation
