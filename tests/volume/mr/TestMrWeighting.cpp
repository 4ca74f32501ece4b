// SPDX-License-Identifier: Apache-2.0
/// @file TestMrWeighting.cpp
/// @brief The MR weighting rule (volume/mr/MrWeighting.h) on the shared real series,
/// read from their DICOM headers and from the reference converter's BIDS
/// sidecars, and on hand-made field sets of other vendors and weightings; the
/// BIDS sidecar reader and its refusals.

#include "core/Errors.h"
#include "volume/mr/MrWeighting.h"

#include "common/SharedData.h"
#include "common/TempDirTest.h"
#include "common/Tolerances.h"

#include <gdcmReader.h>
#include <gdcmStringFilter.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace voxhap::volume {
/// Failure messages print the kind's name, not its bytes.
inline void PrintTo(MrWeightingKind k, std::ostream* os) { *os << mrWeightingName(k); }
} // namespace voxhap::volume

// A named namespace: test sources are compiled in unity batches too.
namespace mrweighting_test {

namespace fs = std::filesystem;
using namespace voxhap::volume;
using voxhap::test::TempDirTest;

/// The closed forms of the T1 sensitivity below hold in the limit TR ≪ T1;
/// at TR/T1 = 1/900 the first neglected term is of order TR/T1 ≈ 1e-3.
constexpr double kShortTrLimit = 2e-3;

/// The header fields the rule reads, from one DICOM file (what a loader passes).
/// Siemens stores the b-value privately in (0019,100C).
MrSequenceFields dicomFields(const fs::path& file)
{
    gdcm::Reader r;
    r.SetFileName(file.string().c_str());
    if (!r.Read()) throw std::runtime_error("cannot read " + file.string());
    gdcm::StringFilter sf;
    sf.SetFile(r.GetFile());
    const gdcm::DataSet& ds = r.GetFile().GetDataSet();
    const auto str = [&](uint16_t g, uint16_t e) -> std::string {
        const gdcm::Tag t(g, e);
        if (!ds.FindDataElement(t)) return {};
        std::string s = sf.ToString(t);
        while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.pop_back();
        return s;
    };
    const auto num = [&](uint16_t g, uint16_t e) -> std::optional<double> {
        const std::string s = str(g, e);
        if (s.find_first_not_of(' ') == std::string::npos) return std::nullopt;
        return std::stod(s);
    };
    MrSequenceFields f;
    f.scanningSequence = str(0x0018, 0x0020);
    f.sequenceVariant = str(0x0018, 0x0021);
    f.scanOptions = str(0x0018, 0x0022);
    f.sequenceName = str(0x0018, 0x0024);
    f.imageType = str(0x0008, 0x0008);
    f.description = str(0x0008, 0x103E);
    f.protocolName = str(0x0018, 0x1030);
    f.repetitionTimeMs = num(0x0018, 0x0080);
    f.echoTimeMs = num(0x0018, 0x0081);
    f.inversionTimeMs = num(0x0018, 0x0082);
    f.flipAngleDeg = num(0x0018, 0x1314);
    f.bValue = num(0x0019, 0x100C);
    f.source = "DICOM headers";
    return f;
}

std::vector<fs::path> dicomFiles(const fs::path& dir)
{
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir)) {
        if (e.path().extension() == ".dcm") files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    return files;
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

MrWeighting classify(const MrSequenceFields& f) { return classifyMrWeighting(f); }

/// The verdict's kind, with its reason in the failure message.
#define EXPECT_KIND(w, k) EXPECT_EQ((w).kind, (k)) << (w).name << ": " << (w).reason

// ---------------------------------------------------------------- the shared series

TEST(MrWeighting, SharedMprageHeadersAreT1Weighted)
{
    VOXHAP_REQUIRE_DIR(voxhap::test::mprageDir());
    const auto files = dicomFiles(voxhap::test::mprageDir());
    ASSERT_EQ(files.size(), 176u);
    // What decides, as the headers give it.
    const MrSequenceFields f = dicomFields(files.front());
    EXPECT_EQ(f.scanningSequence, "GR\\IR");
    EXPECT_EQ(f.sequenceVariant, "SP\\MP");
    EXPECT_EQ(f.sequenceName, "tfl3d1_ns");
    EXPECT_EQ(f.inversionTimeMs, 850.0);
    EXPECT_EQ(f.flipAngleDeg, 9.0); // a small flip: the inversion, not the flip, makes it T1-weighted
    for (const fs::path& file : {files.front(), files[files.size() / 2], files.back()}) {
        const MrWeighting w = classify(dicomFields(file));
        EXPECT_KIND(w, MrWeightingKind::T1Weighted);
        EXPECT_TRUE(w.fillsT1());
        EXPECT_TRUE(contains(w.reason, "TI 850 ms")) << w.reason;
        EXPECT_TRUE(contains(w.reason, "(from DICOM headers)")) << w.reason;
    }
}

TEST(MrWeighting, SharedFieldMapIsAFieldMapWhateverItsContrast)
{
    VOXHAP_REQUIRE_DIR(voxhap::test::fieldMapDir());
    const auto files = dicomFiles(voxhap::test::fieldMapDir());
    ASSERT_EQ(files.size(), 36u);
    std::set<double> echoTimes;
    for (const fs::path& file : files) {
        const MrSequenceFields f = dicomFields(file);
        EXPECT_EQ(f.sequenceName, "fm2d2r");
        EXPECT_EQ(f.repetitionTimeMs, 488.0);
        EXPECT_EQ(f.flipAngleDeg, 60.0);
        EXPECT_TRUE(contains(f.imageType, "\\M\\")) << "magnitude: " << f.imageType;
        echoTimes.insert(*f.echoTimeMs);
        const MrWeighting w = classify(f);
        EXPECT_KIND(w, MrWeightingKind::FieldMap);
        EXPECT_FALSE(w.fillsT1()) << file;
        EXPECT_TRUE(contains(w.reason, "fm2d2r")) << w.reason;
    }
    EXPECT_EQ(echoTimes, (std::set<double>{4.92, 7.38})) << "both echoes were classified";

    // Without the sequence name and descriptions, the same contrast fields are
    // judged as a spoiled gradient echo: the purpose, not the contrast, decided.
    MrSequenceFields bare = dicomFields(files.front());
    bare.sequenceName.clear();
    bare.description.clear();
    bare.protocolName.clear();
    EXPECT_NE(classify(bare).kind, MrWeightingKind::FieldMap);
}

TEST(MrWeighting, SharedDiffusionMosaicsAreDiffusion)
{
    VOXHAP_REQUIRE_DIR(voxhap::test::dwiMosaicDir());
    const auto files = dicomFiles(voxhap::test::dwiMosaicDir());
    ASSERT_EQ(files.size(), 13u);
    std::set<double> bValues;
    std::set<std::string> names;
    for (const fs::path& file : files) {
        const MrSequenceFields f = dicomFields(file);
        EXPECT_EQ(f.scanningSequence, "EP");
        EXPECT_TRUE(contains(f.imageType, "DIFFUSION")) << f.imageType;
        if (f.bValue) bValues.insert(*f.bValue);
        names.insert(f.sequenceName);
        const MrWeighting w = classify(f);
        EXPECT_KIND(w, MrWeightingKind::Diffusion);
        EXPECT_FALSE(w.fillsT1());
    }
    EXPECT_EQ(bValues, (std::set<double>{0.0, 1000.0}));
    EXPECT_TRUE(names.count("*ep_b0") && names.count("*ep_b1000#1")) << "b0 and diffusion-weighted volumes both seen";

    // The sequence name alone (no ImageType, no b-value) also says diffusion.
    MrSequenceFields nameOnly;
    nameOnly.sequenceName = "*ep_b1000#1";
    nameOnly.scanningSequence = "EP";
    EXPECT_KIND(classify(nameOnly), MrWeightingKind::Diffusion);
}

TEST(MrWeighting, SharedDiffusionSidecarIsDiffusion)
{
    VOXHAP_REQUIRE_DIR(voxhap::test::prismaReferenceDir());
    const fs::path json = voxhap::test::prismaReferenceDir() / "ep2d_diff_mddw_20_p2_20220407150138.json";
    const BidsSidecar s = readBidsSidecar(json);
    EXPECT_EQ(s.fields.sequenceName, "*ep_b0");
    EXPECT_EQ(s.fields.imageType, "ORIGINAL\\PRIMARY\\DIFFUSION\\NONE\\ND\\NORM\\MOSAIC");
    EXPECT_NEAR(*s.fields.repetitionTimeMs, 3000.0, 3000.0 * voxhap::test::kUnitConversionRelative);
    EXPECT_NEAR(*s.fields.echoTimeMs, 69.0, 69.0 * voxhap::test::kUnitConversionRelative);
    const MrWeighting w = classify(s.fields);
    EXPECT_KIND(w, MrWeightingKind::Diffusion);
    EXPECT_FALSE(w.fillsT1());
    EXPECT_TRUE(contains(w.reason, "BIDS sidecar ep2d_diff_mddw_20_p2_20220407150138.json")) << w.reason;
}

TEST(MrWeighting, SharedFlash2dHeadersAreT1Weighted)
{
    VOXHAP_REQUIRE_DIR(voxhap::test::flash2dDir());
    const auto files = dicomFiles(voxhap::test::flash2dDir());
    ASSERT_EQ(files.size(), 35u);
    for (const fs::path& file : files) {
        const MrSequenceFields f = dicomFields(file);
        EXPECT_EQ(f.sequenceName, "*fl2d1");
        EXPECT_EQ(f.sequenceVariant, "SP\\OSP");
        const MrWeighting w = classify(f);
        EXPECT_KIND(w, MrWeightingKind::T1Weighted);
        EXPECT_TRUE(w.fillsT1());
        EXPECT_TRUE(contains(w.reason, "T1 sensitivity")) << w.reason;
    }
}

TEST(MrWeighting, SharedFlash2dSidecarIsT1WeightedAndAgreesWithTheHeaders)
{
    VOXHAP_REQUIRE_DIR(voxhap::test::prismaReferenceDir());
    const BidsSidecar s = readBidsSidecar(voxhap::test::prismaReferenceDir() / "t1_fl2d_sag_20220407150138.json");
    // BIDS seconds (RepetitionTime 0.3, EchoTime 0.00246) come back in ms.
    EXPECT_NEAR(*s.fields.repetitionTimeMs, 300.0, 300.0 * voxhap::test::kUnitConversionRelative);
    EXPECT_NEAR(*s.fields.echoTimeMs, 2.46, 2.46 * voxhap::test::kUnitConversionRelative);
    EXPECT_EQ(s.fields.inversionTimeMs, std::nullopt);
    EXPECT_EQ(s.fields.flipAngleDeg, 80.0);
    EXPECT_EQ(s.fields.scanningSequence, "GR");
    EXPECT_EQ(s.fields.sequenceVariant, "SP\\OSP");
    EXPECT_EQ(s.fields.imageType, "ORIGINAL\\PRIMARY\\M\\NORM\\DIS2D\\MAGNITUDE");
    EXPECT_EQ(s.fields.description, "t1_fl2d_sag");
    EXPECT_EQ(s.modality, "MR");
    EXPECT_EQ(s.fieldStrengthT, 3.0);
    const MrWeighting w = classify(s.fields);
    EXPECT_KIND(w, MrWeightingKind::T1Weighted);
    EXPECT_TRUE(contains(w.reason, "flip 80")) << w.reason;

    VOXHAP_REQUIRE_DIR(voxhap::test::flash2dDir());
    const MrSequenceFields d = dicomFields(dicomFiles(voxhap::test::flash2dDir()).front());
    EXPECT_NEAR(
        *s.fields.repetitionTimeMs, *d.repetitionTimeMs, *d.repetitionTimeMs * voxhap::test::kUnitConversionRelative);
    EXPECT_NEAR(*s.fields.echoTimeMs, *d.echoTimeMs, *d.echoTimeMs * voxhap::test::kUnitConversionRelative);
    EXPECT_EQ(s.fields.flipAngleDeg, d.flipAngleDeg);
    EXPECT_EQ(classify(d).kind, w.kind);
}

// ---------------------------------------------------------------- other vendors and weightings

MrSequenceFields fields(std::string ss, std::string sv, std::string name, std::optional<double> tr,
    std::optional<double> te, std::optional<double> ti = std::nullopt, std::optional<double> flip = std::nullopt)
{
    MrSequenceFields f;
    f.scanningSequence = std::move(ss);
    f.sequenceVariant = std::move(sv);
    f.sequenceName = std::move(name);
    f.repetitionTimeMs = tr;
    f.echoTimeMs = te;
    f.inversionTimeMs = ti;
    f.flipAngleDeg = flip;
    return f;
}

TEST(MrWeighting, SiemensTurboSpinEchoFollowsTheTrTeTable)
{
    const MrWeighting t2 = classify(fields("SE", "SK\\SP\\OSP", "*tse2d1_15", 4000, 100, std::nullopt, 150));
    EXPECT_KIND(t2, MrWeightingKind::T2Weighted);
    const MrWeighting pd = classify(fields("SE", "SK\\SP\\OSP", "*tse2d1_7", 3000, 12, std::nullopt, 150));
    EXPECT_KIND(pd, MrWeightingKind::PdWeighted);
    const MrWeighting t1 = classify(fields("SE", "SK\\SP\\OSP", "*tse2d1_3", 650, 9.5, std::nullopt, 150));
    EXPECT_KIND(t1, MrWeightingKind::T1Weighted);
    EXPECT_TRUE(contains(t1.reason, "TR 650 ms")) << t1.reason;
    for (const auto& w : {t2, pd}) EXPECT_FALSE(w.fillsT1()) << w.name;
}

TEST(MrWeighting, GeSpinEchoWithShortTrAndTeIsT1Weighted)
{
    MrSequenceFields f = fields("SE", "NONE", "", 500, 10);
    f.description = "Ax T2 do not trust me"; // headers outrank the description
    EXPECT_KIND(classify(f), MrWeightingKind::T1Weighted);
}

TEST(MrWeighting, InversionTimeSeparatesStirT1AndFlair)
{
    const MrWeighting flair = classify(fields("SE\\IR", "SK\\SP\\MP", "*tir2d1_16", 9000, 81, 2500, 150));
    EXPECT_KIND(flair, MrWeightingKind::Flair);
    const MrWeighting stir = classify(fields("SE\\IR", "SK\\SP\\MP", "*tir2d1_13", 3500, 40, 150, 150));
    EXPECT_KIND(stir, MrWeightingKind::Stir);
    EXPECT_FALSE(stir.fillsT1());
    // The boundaries, on an inversion-prepared gradient echo.
    const auto atTi = [](double ti) {
        return classify(fields("GR\\IR", "SK\\SP\\MP", "*tfl3d1", 2300, 3, ti, 9)).kind;
    };
    EXPECT_EQ(atTi(kMrStirMaxTiMs), MrWeightingKind::Stir);
    EXPECT_EQ(atTi(kMrStirMaxTiMs + 1), MrWeightingKind::T1Weighted);
    EXPECT_EQ(atTi(kMrFlairMinTiMs - 1), MrWeightingKind::T1Weighted);
    EXPECT_EQ(atTi(kMrFlairMinTiMs), MrWeightingKind::Flair);
    // T1-FLAIR (spin echo, TI in the T1 range, short TE) is T1-weighted.
    EXPECT_KIND(classify(fields("SE\\IR", "SK\\SP\\MP", "*tir2d1_7", 2000, 9, 860, 150)), MrWeightingKind::T1Weighted);
}

TEST(MrWeighting, GeInversionPreparedAndSpoiledGradientEchoesAreT1Weighted)
{
    // BRAVO (IR-prepared fast SPGR): GE writes no SP and no IR in ScanningSequence; the TI says it.
    MrSequenceFields bravo = fields("GR", "SS\\SK", "efgre3d", 8.2, 3.2, 450, 12);
    bravo.scanOptions = "FAST_GEMS\\EDR_GEMS\\IR_GEMS";
    const MrWeighting b = classify(bravo);
    EXPECT_KIND(b, MrWeightingKind::T1Weighted);
    EXPECT_TRUE(contains(b.reason, "TI 450 ms")) << b.reason;
    // FSPGR without preparation: judged by its flip against the Ernst angle.
    const MrWeighting fspgr = classify(fields("GR", "SS\\SK", "efgre3d", 7.6, 2.9, std::nullopt, 12));
    EXPECT_KIND(fspgr, MrWeightingKind::T1Weighted);
    EXPECT_TRUE(contains(fspgr.reason, "Ernst angle")) << fspgr.reason;
    // GE's 3D MP-RAGE, as dcm_qa_ge's reference sidecar gives it: ScanningSequence RM\IR.
    EXPECT_KIND(classify(fields("RM\\IR", "NONE", "", 2217.66, 3.172, 1000, 8)), MrWeightingKind::T1Weighted);
}

TEST(MrWeighting, PhilipsTurboFieldEchoIsT1WeightedByItsName)
{
    // T1-TFE: flip 8° at TR 8 ms would be PD-weighted for a plain spoiled gradient
    // echo; its inversion prepulse makes it T1-weighted, and Philips names it so.
    MrSequenceFields f = fields("GR", "SK\\MP", "T1TFE", 8.1, 3.7, std::nullopt, 8);
    const MrWeighting w = classify(f);
    EXPECT_KIND(w, MrWeightingKind::T1Weighted);
    EXPECT_TRUE(contains(w.reason, "vendor")) << w.reason;
    f.sequenceName = "T1FFE";
    f.sequenceVariant = "SP";
    f.repetitionTimeMs = 25;
    f.flipAngleDeg = 30;
    EXPECT_KIND(classify(f), MrWeightingKind::T1Weighted);
    EXPECT_KIND(classify(fields("GR", "SK", "B-TFE", 4.4, 2.2, std::nullopt, 60)), MrWeightingKind::SteadyState);
}

TEST(MrWeighting, SpoiledGradientEchoIsT1OnlyWithAFlipWellAboveErnst)
{
    // 3D FLASH at 1.5 T, TR 20 ms, flip 25° (Ernst ≈ 12°): T1-weighted.
    EXPECT_KIND(classify(fields("GR", "SP", "*fl3d1", 20, 4.6, std::nullopt, 25)), MrWeightingKind::T1Weighted);
    // VIBE, TR 5 ms, flip 10° (Ernst ≈ 6°): T1-weighted.
    EXPECT_KIND(classify(fields("GR", "SP", "*fl3d2", 5, 2, std::nullopt, 10)), MrWeightingKind::T1Weighted);
    // Same TR, flip 5°: proton-density-weighted.
    const MrWeighting pd = classify(fields("GR", "SP", "*fl3d1", 20, 4, std::nullopt, 5));
    EXPECT_KIND(pd, MrWeightingKind::PdWeighted);
    EXPECT_FALSE(pd.fillsT1());
    // Long TE: T2*-weighted whatever the flip.
    EXPECT_KIND(classify(fields("GR", "SP", "*fl2d1", 700, 20, std::nullopt, 20)), MrWeightingKind::T2StarWeighted);
    // Spoiling not given and a short TE: the fields do not decide.
    EXPECT_KIND(classify(fields("GR", "SS", "", 20, 4, std::nullopt, 25)), MrWeightingKind::Unknown);
}

TEST(MrWeighting, SusceptibilityAndBoldAreNotT1)
{
    MrSequenceFields swi = fields("GR", "SP", "*swi3d1r", 28, 20, std::nullopt, 15);
    swi.imageType = "ORIGINAL\\PRIMARY\\M\\ND\\NORM";
    EXPECT_KIND(classify(swi), MrWeightingKind::Susceptibility);
    MrSequenceFields swan = fields("GR", "", "", 40, 25, std::nullopt, 15);
    swan.description = "Ax SWAN";
    EXPECT_KIND(classify(swan), MrWeightingKind::Susceptibility);

    MrSequenceFields bold = fields("EP", "SK\\SS", "*epfid2d1_64", 2000, 30, std::nullopt, 90);
    const MrWeighting t2star = classify(bold);
    EXPECT_KIND(t2star, MrWeightingKind::T2StarWeighted); // the contrast alone
    bold.description = "ep2d_bold_rest";
    EXPECT_KIND(classify(bold), MrWeightingKind::Functional); // the purpose, when stated
    MrSequenceFields fmri = fields("EP", "SK\\SS", "*epfid2d1_64", 2000, 30, std::nullopt, 90);
    fmri.imageType = "ORIGINAL\\PRIMARY\\FMRI\\NONE\\ND\\MOSAIC";
    EXPECT_KIND(classify(fmri), MrWeightingKind::Functional);
}

TEST(MrWeighting, ImageTypeDecidesFirst)
{
    // MPRAGE-like fields, but the image is a T1 map, a phase image or an ADC map.
    MrSequenceFields f = fields("GR\\IR", "SK\\SP\\MP", "*tfl3d1_16", 5000, 2.9, 700, 4);
    f.imageType = "DERIVED\\PRIMARY\\T1 MAP\\ND";
    const MrWeighting map = classify(f);
    EXPECT_KIND(map, MrWeightingKind::T1Map);
    EXPECT_TRUE(map.fillsT1());
    f.imageType = "ORIGINAL\\PRIMARY\\P\\ND";
    EXPECT_KIND(classify(f), MrWeightingKind::Phase);
    f.imageType = "DERIVED\\PRIMARY\\DIFFUSION\\ADC\\ND";
    EXPECT_KIND(classify(f), MrWeightingKind::Diffusion);
    f.imageType = "DERIVED\\PRIMARY\\T2 MAP\\ND";
    EXPECT_KIND(classify(f), MrWeightingKind::OtherMap);
    f.imageType = "DERIVED\\PRIMARY\\MIP\\ND";
    EXPECT_KIND(classify(f), MrWeightingKind::Derived);
    // The phase difference of a field-map sequence is a field map.
    MrSequenceFields fm = fields("GR", "SP", "fm2d2r", 488, 7.38, std::nullopt, 60);
    fm.imageType = "ORIGINAL\\PRIMARY\\P\\ND";
    EXPECT_KIND(classify(fm), MrWeightingKind::FieldMap);
}

TEST(MrWeighting, FieldMapPurposeOutranksT1Contrast)
{
    // A field map whose TR and flip alone would read as T1-weighted.
    MrSequenceFields f = fields("GR", "SP", "", 20, 2.3, std::nullopt, 30);
    ASSERT_EQ(classify(f).kind, MrWeightingKind::T1Weighted) << "the contrast alone";
    for (const char* description : {"B0map", "gre_field_mapping", "fmap_acq-dual", "FieldMap_AP"}) {
        f.description = description;
        const MrWeighting w = classify(f);
        EXPECT_KIND(w, MrWeightingKind::FieldMap) << description;
        EXPECT_TRUE(contains(w.reason, "whatever its TR, TE and flip angle")) << w.reason;
    }
}

TEST(MrWeighting, OnlyTheDescriptionDecidesWhenNothingElseDoes)
{
    MrSequenceFields f;
    f.description = "t1_mprage_sag";
    const MrWeighting w = classify(f);
    EXPECT_KIND(w, MrWeightingKind::T1Weighted);
    EXPECT_TRUE(contains(w.reason, "only the description decided")) << w.reason;
    EXPECT_TRUE(contains(w.reason, "t1_mprage_sag")) << w.reason;

    // A spin echo with an intermediate TR: the fields say why they did not decide.
    MrSequenceFields se = fields("SE", "SK", "*tse2d1_3", 1000, 12);
    const MrWeighting undecided = classify(se);
    EXPECT_KIND(undecided, MrWeightingKind::Unknown);
    EXPECT_TRUE(contains(undecided.reason, "between")) << undecided.reason;
    se.protocolName = "t1_tse_tra";
    const MrWeighting byName = classify(se);
    EXPECT_KIND(byName, MrWeightingKind::T1Weighted);
    EXPECT_TRUE(contains(byName.reason, "ProtocolName")) << byName.reason;
    EXPECT_TRUE(contains(byName.reason, "the sequence fields did not")) << byName.reason;
}

TEST(MrWeighting, NothingAtAllIsUnknownAndNeverT1)
{
    const MrWeighting w = classify(MrSequenceFields{});
    EXPECT_KIND(w, MrWeightingKind::Unknown);
    EXPECT_FALSE(w.fillsT1());
    EXPECT_EQ(w.name, "unknown");
    EXPECT_TRUE(contains(w.reason, "no sequence fields")) << w.reason;
}

TEST(MrWeighting, DescriptionKeywordsMatchWholeWords)
{
    const auto byDescription = [](const char* d) {
        MrSequenceFields f;
        f.description = d;
        return classify(f).kind;
    };
    using K = MrWeightingKind;
    EXPECT_EQ(byDescription("T10_delay"), K::Unknown) << "T1 inside T10";
    EXPECT_EQ(byDescription("updated protocol"), K::Unknown) << "PD inside UPDATED";
    EXPECT_EQ(byDescription("spd_2"), K::Unknown) << "PD inside SPD";
    EXPECT_EQ(byDescription("Sag T1w"), K::T1Weighted);
    EXPECT_EQ(byDescription("sT1W_3D_TFE"), K::T1Weighted) << "Philips's s prefix";
    EXPECT_EQ(byDescription("3DT1_post"), K::T1Weighted);
    EXPECT_EQ(byDescription("Sag T1 FSPGR"), K::T1Weighted);
    EXPECT_EQ(byDescription("T1 FLAIR sag"), K::T1Weighted) << "T1-FLAIR is T1-weighted";
    EXPECT_EQ(byDescription("T1 map"), K::T1Map);
    EXPECT_EQ(byDescription("ax_flair"), K::Flair);
    EXPECT_EQ(byDescription("t2_tse_tra"), K::T2Weighted);
    EXPECT_EQ(byDescription("T2*_gre"), K::T2StarWeighted);
    EXPECT_EQ(byDescription("Sag PDw FS"), K::PdWeighted);
    EXPECT_EQ(byDescription("cor_stir"), K::Stir);
    EXPECT_EQ(byDescription("PD_T2_tse"), K::Unknown) << "two contrasts named";
    EXPECT_EQ(byDescription("T1_T2_combined"), K::Unknown) << "T1 and another contrast named";
    EXPECT_EQ(byDescription("AAHead_Scout"), K::Localizer);
    EXPECT_EQ(byDescription("DTI_64dir"), K::Diffusion);
    EXPECT_EQ(byDescription("TOF_3D_multi-slab"), K::Angiography);
    EXPECT_EQ(byDescription("pCASL"), K::Perfusion);
}

TEST(MrWeighting, OnlyT1MapsAndT1WeightedFillT1)
{
    for (int k = 0; k <= int(MrWeightingKind::Unknown); ++k) {
        MrWeighting w;
        w.kind = MrWeightingKind(k);
        const bool t1 = w.kind == MrWeightingKind::T1Map || w.kind == MrWeightingKind::T1Weighted;
        EXPECT_EQ(w.fillsT1(), t1) << mrWeightingName(w.kind);
        EXPECT_FALSE(mrWeightingName(w.kind).empty());
    }
    EXPECT_EQ(mrWeightingName(MrWeightingKind::T1Map), "T1 map");
    EXPECT_EQ(mrWeightingName(MrWeightingKind::T1Weighted), "T1-weighted");
    EXPECT_EQ(mrWeightingName(MrWeightingKind::PdWeighted), "PD-weighted");
    EXPECT_EQ(mrWeightingName(MrWeightingKind::T2Weighted), "T2-weighted");
    EXPECT_EQ(mrWeightingName(MrWeightingKind::Diffusion), "diffusion");
    // A verdict's name is its kind's name.
    const MrWeighting w = classify(fields("SE", "", "", 4000, 100));
    EXPECT_EQ(w.name, mrWeightingName(w.kind));
}

TEST(MrWeighting, T1SensitivityMatchesItsClosedForms)
{
    const double t1 = kMrReferenceT1Ms, tr = 1.0; // TR ≪ T1
    const double ernst = std::acos(std::exp(-tr / t1)) * 180.0 / std::numbers::pi;
    EXPECT_EQ(spoiledGreT1Sensitivity(tr, 0.0, t1), 0.0) << "no flip, no T1 weighting";
    EXPECT_NEAR(spoiledGreT1Sensitivity(tr, ernst, t1), 0.5, kShortTrLimit)
        << "T1 and PD weigh equally at the Ernst angle";
    EXPECT_NEAR(spoiledGreT1Sensitivity(tr, 2 * ernst, t1), 0.8, kShortTrLimit) << "r²/(1 + r²) with r = 2";
    EXPECT_NEAR(spoiledGreT1Sensitivity(tr, 90.0, t1), 1.0, kShortTrLimit) << "S ∝ TR/T1";
    // 90° at the spin-echo short-TR limit: (TR/T1)·E1/(1 − E1), exactly.
    const double x = kMrSeShortTrMaxMs / t1, e = std::exp(-x);
    EXPECT_NEAR(spoiledGreT1Sensitivity(kMrSeShortTrMaxMs, 90.0, t1), x * e / (1 - e), 1e-12);
    EXPECT_GE(spoiledGreT1Sensitivity(kMrSeShortTrMaxMs, 90.0, t1), kMrMinT1Sensitivity) << "the two rules agree";
    EXPECT_LT(spoiledGreT1Sensitivity(2 * kMrSeShortTrMaxMs, 90.0, t1), kMrMinT1Sensitivity)
        << "long TR: no T1 weighting";
}

// ---------------------------------------------------------------- BIDS sidecars

TEST(MrWeighting, SidecarPathReplacesTheImageExtension)
{
    EXPECT_EQ(bidsSidecarPath("/d/sub-01_T1w.nii.gz"), fs::path("/d/sub-01_T1w.json"));
    EXPECT_EQ(bidsSidecarPath("/d/x.nii"), fs::path("/d/x.json"));
    EXPECT_EQ(bidsSidecarPath("/d/x.nrrd"), fs::path("/d/x.json"));
    EXPECT_EQ(bidsSidecarPath("/d/x.mha"), fs::path("/d/x.json"));
    EXPECT_EQ(bidsSidecarPath("/d/x.mhd"), fs::path("/d/x.json"));
    EXPECT_EQ(bidsSidecarPath("a.b.nii.gz"), fs::path("a.b.json"));
    EXPECT_EQ(bidsSidecarPath("X.NII.GZ"), fs::path("X.json"));
}

class MrWeightingSidecar : public TempDirTest {
protected:
    fs::path write(const std::string& name, const std::string& text)
    {
        const fs::path p = mDir / name;
        std::ofstream(p) << text;
        return p;
    }
};

TEST_F(MrWeightingSidecar, TimesInSecondsComeBackInMilliseconds)
{
    const fs::path p = write("mprage.json", R"({
        "Modality": "MR", "MagneticFieldStrength": 1.5,
        "ScanningSequence": ["GR", "IR"], "SequenceVariant": "SK\\SP\\MP",
        "SequenceName": "*tfl3d1_16ns", "ImageType": ["ORIGINAL", "PRIMARY", "M", "ND"],
        "SeriesDescription": "T1_MPRAGE", "ProtocolName": "T1_MPRAGE",
        "RepetitionTime": 2.3, "EchoTime": [0.00298, 0.005], "InversionTime": 0.9, "FlipAngle": 9,
        "SliceTiming": [0, 1.2]
    })");
    const BidsSidecar s = readBidsSidecar(p);
    using voxhap::test::kUnitConversionRelative;
    EXPECT_NEAR(*s.fields.repetitionTimeMs, 2300.0, 2300.0 * kUnitConversionRelative);
    EXPECT_NEAR(*s.fields.echoTimeMs, 2.98, 2.98 * kUnitConversionRelative) << "an array: its first echo";
    EXPECT_NEAR(*s.fields.inversionTimeMs, 900.0, 900.0 * kUnitConversionRelative);
    EXPECT_EQ(s.fields.flipAngleDeg, 9.0);
    EXPECT_EQ(s.fields.scanningSequence, "GR\\IR");
    EXPECT_EQ(s.fields.imageType, "ORIGINAL\\PRIMARY\\M\\ND");
    EXPECT_EQ(s.fields.source, "BIDS sidecar mprage.json");
    EXPECT_EQ(s.modality, "MR");
    EXPECT_EQ(s.fieldStrengthT, 1.5);
    EXPECT_EQ(s.file, p);
    EXPECT_KIND(classify(s.fields), MrWeightingKind::T1Weighted);
}

TEST_F(MrWeightingSidecar, MalformedJsonIsRefusedNamingTheFile)
{
    const fs::path p = write("broken.json", "{\n  \"RepetitionTime\": 2.3,\n}\n");
    voxhap::test::expectRefused<voxhap::IoError>([](const fs::path& f) { readBidsSidecar(f); }, p, "malformed JSON");
    voxhap::test::expectRefused<voxhap::IoError>(
        [](const fs::path& f) { readBidsSidecar(f); }, write("array.json", "[1, 2]"), "JSON object");
}

TEST_F(MrWeightingSidecar, WrongFieldTypesAreRefusedNamingTheField)
{
    const auto refused = [&](const char* name, const std::string& text, const std::string& field) {
        voxhap::test::expectRefused<voxhap::IoError>(
            [](const fs::path& f) { readBidsSidecar(f); }, write(name, text), field);
    };
    refused("tr-string.json", R"({"RepetitionTime": "2.3"})", "RepetitionTime: must be a number");
    refused("flip-negative.json", R"({"FlipAngle": -9})", "FlipAngle");
    refused("imagetype-number.json", R"({"ImageType": 5})", "ImageType");
    refused("imagetype-mixed.json", R"({"ImageType": ["ORIGINAL", 2]})", "ImageType");
    refused("name-array.json", R"({"SequenceName": ["tfl"]})", "SequenceName: must be a string");
    refused("te-empty.json", R"({"EchoTime": []})", "EchoTime");
    // Milliseconds where BIDS wants seconds would read 1000 times too long: refused.
    refused("tr-ms.json", R"({"RepetitionTime": 2300})", "RepetitionTime");
    refused("te-ms.json", R"({"EchoTime": 30})", "EchoTime");
    refused("ti-ms.json", R"({"InversionTime": 900})", "InversionTime");
}

TEST_F(MrWeightingSidecar, MissingSidecarIsRefusedOrAbsent)
{
    voxhap::test::expectRefused<voxhap::IoError>(
        [](const fs::path& f) { readBidsSidecar(f); }, mDir / "none.json", "cannot open");
    EXPECT_FALSE(readBidsSidecarBeside(mDir / "lonely.nii.gz").has_value());
    write("x.json", R"({"SeriesDescription": "t1_mprage_sag"})");
    const auto s = readBidsSidecarBeside(mDir / "x.nii.gz");
    ASSERT_TRUE(s.has_value());
    EXPECT_EQ(s->file, mDir / "x.json");
    EXPECT_KIND(classify(s->fields), MrWeightingKind::T1Weighted);
}

} // namespace mrweighting_test

#undef EXPECT_KIND
