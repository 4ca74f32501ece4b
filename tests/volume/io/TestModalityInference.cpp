// SPDX-License-Identifier: Apache-2.0
/// @file TestModalityInference.cpp
/// @brief NIfTI and NRRD carry no modality (issue 27 item 8): CT or MR from
/// the values, a BIDS sidecar's weighting, the user's declarations, and a
/// refusal for values that are neither.

#include "common/TempDirTest.h"

#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/VolumeFile.h"
#include "volume/io/ModalityInference.h"

#include <nifti2_io.h>

#include <cmath>
#include <fstream>
#include <functional>

namespace {

namespace fs = std::filesystem;
using namespace voxhap::volume;

constexpr int kN = 32;

/// A head-sized ball in a 32³ grid: @p f(r, i, j, k) gives each voxel's value, r the distance from the centre [voxels].
fs::path writeNifti(
    const fs::path& file, int datatype, const std::function<double(double, int, int, int)>& f, double voxelMm = 1.0)
{
    nifti_set_debug_level(0);
    const int64_t dims[8] = {3, kN, kN, kN, 1, 1, 1, 1};
    nifti_image* nim = nifti_make_new_nim(dims, datatype, 1);
    for (int k = 0; k < kN; ++k) {
        for (int j = 0; j < kN; ++j) {
            for (int i = 0; i < kN; ++i) {
                const double r = std::sqrt(double((i - 16) * (i - 16) + (j - 16) * (j - 16) + (k - 16) * (k - 16)));
                const std::size_t n = std::size_t((k * kN + j) * kN + i);
                const double v = f(r, i, j, k);
                if (datatype == DT_UINT8)
                    static_cast<std::uint8_t*>(nim->data)[n] = std::uint8_t(v);
                else
                    static_cast<float*>(nim->data)[n] = float(v);
            }
        }
    }
    nim->pixdim[1] = nim->pixdim[2] = nim->pixdim[3] = float(voxelMm);
    nim->dx = nim->dy = nim->dz = float(voxelMm);
    nim->qform_code = NIFTI_XFORM_SCANNER_ANAT;
    nim->quatern_b = nim->quatern_c = nim->quatern_d = 0;
    nim->qfac = 1;
    nifti_set_filenames(nim, file.string().c_str(), 0, 1);
    nifti_image_write(nim);
    nifti_image_free(nim);
    return file;
}

/// Air noise that is never negative: a small deterministic pattern of 0..5.
double airNoise(int i, int j, int k) { return double((i * 7 + j * 13 + k * 29) % 6); }

/// A T1-weighted head as 8-bit intensities (0..254): scalp fat bright, brain
/// darker, a dark ventricle; the air is noise around zero.
double t1wHead(double r, int i, int j, int k)
{
    if (r > 13) return airNoise(i, j, k);
    if (r > 11) return 220; // fat
    if (r < 3) return 40;   // fluid
    return 110;             // muscle-like grey
}

/// A CT of the same ball: air, a bone shell, soft tissue.
double ctHead(double r, int, int, int)
{
    if (r > 13) return -1000;
    if (r > 11) return 900;
    return 35;
}

void writeSidecar(const fs::path& image, const std::string& json)
{
    std::string name = image.filename().string();
    name = name.substr(0, name.find('.'));
    std::ofstream(image.parent_path() / (name + ".json")) << json;
}

class ModalityInference : public voxhap::test::TempDirTest { };

TEST_F(ModalityInference, CtIsInferredFromAirAndWater)
{
    const fs::path p = writeNifti(mDir / "ct.nii.gz", DT_FLOAT32, ctHead);
    const Volume v = loadVolume(p);
    ASSERT_TRUE(v.has(Channel::Hu));
    EXPECT_EQ(v.metadata().modality, "CT");
    EXPECT_EQ(v.metadata().modalitySource, FactSource::Data);
    EXPECT_NE(v.metadata().modalityReason.find("inferred from the data"), std::string::npos);
    EXPECT_NE(v.metadata().modalityReason.find("air"), std::string::npos);
    // The air below −950 is inactive, the tissue exact.
    auto acc = huGrid(v)->getConstAccessor();
    EXPECT_FALSE(acc.isValueOn({0, 0, 0}));
    EXPECT_EQ(acc.getValue({16, 16, 16}), 35.0f);
}

TEST_F(ModalityInference, T1WeightedNiftiIsMrOfUnknownWeightingUntilDeclared)
{
    // The issue's case: 0..254 T1-weighted intensities were read as CT HU.
    const fs::path p = writeNifti(mDir / "t1w.nii", DT_UINT8, t1wHead);
    const Volume v = loadVolume(p);
    EXPECT_EQ(v.metadata().modality, "MR");
    EXPECT_FALSE(v.has(Channel::Hu));
    EXPECT_FALSE(v.has(Channel::T1)); // no sidecar, no declaration: never T1
    ASSERT_TRUE(v.has(Channel::Intensity));
    EXPECT_EQ(v.metadata().mrWeighting, voxhap::volume::MrWeightingKind::Unknown);
    EXPECT_NE(v.metadata().extra.at("mr_weighting_reason").find("--t1-weighted"), std::string::npos);
    EXPECT_EQ(intensityGrid(v)->getConstAccessor().getValue({16, 16, 20}), 110.0f);

    // Declared T1-weighted, but 27 mm across: a head or a limb, whose
    // brightest class is not a trunk's fat; not normalised, and says why.
    LoadOptions declared;
    declared.dicom.t1Weighted = true;
    const Volume head = loadVolume(p, declared);
    EXPECT_FALSE(head.has(Channel::T1));
    EXPECT_NE(head.metadata().extra.at("t1_norm_refused").find("mm across"), std::string::npos);

    // The same values in 10 mm voxels: a 270 mm trunk. Normalised per scan,
    // fat and muscle pinned to the table at the assumed field (stated).
    const fs::path trunk = writeNifti(mDir / "trunk.nii", DT_UINT8, t1wHead, 10.0);
    const Volume t1 = loadVolume(trunk, declared);
    ASSERT_TRUE(t1.has(Channel::T1));
    EXPECT_EQ(t1.metadata().t1Units, "ms");
    EXPECT_NE(t1.metadata().extra.at("mr_weighting_reason").find("declared"), std::string::npos);
    EXPECT_EQ(t1.metadata().fieldStrength, FieldStrength::T1_5);
    EXPECT_EQ(t1.metadata().fieldStrengthSource, FactSource::Assumed);
    EXPECT_NEAR(t1Grid(t1)->getConstAccessor().getValue({16, 16, 28}), 290.0, 1e-3); // fat at 1.5 T (physics.md §5.1)
}

TEST_F(ModalityInference, BidsSidecarGivesTheWeightingAndFieldStrength)
{
    const fs::path p = writeNifti(mDir / "flash.nii.gz", DT_UINT8, t1wHead, 10.0); // a 270 mm trunk
    writeSidecar(p, R"({"Modality": "MR", "MagneticFieldStrength": 3, "ScanningSequence": "GR",
                        "SequenceVariant": ["SP", "OSP"], "SequenceName": "*fl2d1", "RepetitionTime": 0.3,
                        "EchoTime": 0.00246, "FlipAngle": 80, "ImageType": ["ORIGINAL", "PRIMARY", "M"]})");
    const Volume v = loadVolume(p);
    EXPECT_EQ(v.metadata().mrWeighting, voxhap::volume::MrWeightingKind::T1Weighted);
    ASSERT_TRUE(v.has(Channel::T1));
    EXPECT_EQ(v.metadata().modalitySource, FactSource::Sidecar);
    EXPECT_NE(v.metadata().modalityReason.find("sidecar"), std::string::npos);
    EXPECT_EQ(v.metadata().fieldStrength, FieldStrength::T3);
    EXPECT_EQ(v.metadata().fieldStrengthSource, FactSource::Sidecar);
    EXPECT_NEAR(t1Grid(v)->getConstAccessor().getValue({16, 16, 28}), 382.0, 1e-3); // fat at 3 T

    // A sidecar that says T2: an intensity grid, named.
    writeSidecar(p, R"({"Modality": "MR", "ScanningSequence": "SE", "SequenceName": "*tse2d1_15",
                        "RepetitionTime": 4.0, "EchoTime": 0.1})");
    const Volume t2 = loadVolume(p);
    EXPECT_EQ(t2.metadata().mrWeighting, voxhap::volume::MrWeightingKind::T2Weighted);
    EXPECT_FALSE(t2.has(Channel::T1));
}

TEST_F(ModalityInference, ValuesThatAreNeitherAreRefusedNamingChannel)
{
    // A z-scored image: negative values without the air of a CT.
    const fs::path p =
        writeNifti(mDir / "z.nii", DT_FLOAT32, [](double r, int, int, int) { return r < 10 ? 1.5 : -0.8; });
    try {
        loadVolume(p);
        FAIL() << "a z-scored image loaded as CT or MR";
    } catch (const voxhap::IoError& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.rfind(p.string() + ": modality: ", 0), 0u) << msg;
        EXPECT_NE(msg.find("--channel"), std::string::npos) << msg;
    }
    LoadOptions mr;
    mr.modality = DeclaredModality::Mr;
    const Volume v = loadVolume(p, mr);
    EXPECT_EQ(v.metadata().modality, "MR");
    EXPECT_EQ(v.metadata().modalitySource, FactSource::User);
    EXPECT_NE(v.metadata().modalityReason.find("--channel mr"), std::string::npos);
}

TEST_F(ModalityInference, TheRuleOnItsOwn)
{
    // Direct checks of the thresholds on grids of known content.
    const auto grid = [](std::initializer_list<std::pair<float, int>> values) {
        auto g = FloatGrid::create(-1000.0f);
        int x = 0;
        for (const auto& [v, n] : values) {
            for (int i = 0; i < n; ++i) g->tree().setValueOn(openvdb::Coord(x++, 0, 0), v);
        }
        return g;
    };
    EXPECT_EQ(inferModality(*grid({{0.0f, 10}, {300.0f, 90}})).kind, ModalityGuess::Kind::Mr);
    EXPECT_EQ(inferModality(*grid({{-1000.0f, 50}, {40.0f, 50}})).kind, ModalityGuess::Kind::Ct);
    // Air present but no water or soft tissue (1 %): not CT.
    EXPECT_EQ(inferModality(*grid({{-1000.0f, 500}, {1500.0f, 500}})).kind, ModalityGuess::Kind::Unknown);
    // Ringing of an interpolated MR: −3 against a maximum of 800 (0.4 %).
    EXPECT_EQ(inferModality(*grid({{-3.0f, 5}, {800.0f, 95}})).kind, ModalityGuess::Kind::Mr);
    // Negatives beyond the ringing allowance without air: undecided.
    EXPECT_EQ(inferModality(*grid({{-100.0f, 5}, {800.0f, 95}})).kind, ModalityGuess::Kind::Unknown);
}

TEST_F(ModalityInference, NrrdWithoutVoxhapKeysIsInferredAndAnIntensityGridRoundTrips)
{
    // A plain NRRD as other tools write it: CT values, no voxhap keys.
    {
        std::ofstream out(mDir / "ct.nrrd", std::ios::binary);
        out << "NRRD0004\ntype: short\ndimension: 3\nspace: left-posterior-superior\nsizes: 8 8 8\n"
               "space directions: (1,0,0) (0,1,0) (0,0,1)\nkinds: domain domain domain\nendian: little\n"
               "encoding: raw\nspace origin: (0,0,0)\n\n";
        for (int n = 0; n < 512; ++n) {
            const std::int16_t v = n % 8 < 2 ? -1000 : 50;
            out.write(reinterpret_cast<const char*>(&v), 2);
        }
    }
    EXPECT_EQ(loadVolume(mDir / "ct.nrrd").metadata().modality, "CT");

    // An MR intensity grid saved by voxhap comes back as one, with its weighting.
    const fs::path p = writeNifti(mDir / "mr.nii", DT_UINT8, t1wHead);
    const Volume v = loadVolume(p);
    saveVolume(v, mDir / "mr.nrrd");
    const Volume back = loadVolume(mDir / "mr.nrrd");
    EXPECT_TRUE(back.has(Channel::Intensity));
    EXPECT_FALSE(back.has(Channel::T1));
    EXPECT_EQ(back.metadata().mrWeighting, voxhap::volume::MrWeightingKind::Unknown);
    EXPECT_EQ(intensityGrid(back)->activeVoxelCount(), intensityGrid(v)->activeVoxelCount());
}

} // namespace
