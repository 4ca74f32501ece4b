// SPDX-License-Identifier: Apache-2.0
/// @file TestVolumeMetadata.cpp
/// @brief The typed facts: the field-strength rule, their names as text, and
/// the reading of files written before the facts were typed.

#include "core/Errors.h"
#include "volume/VolumeMetadata.h"

#include <gtest/gtest.h>

namespace voxhap::volume {
namespace {

TEST(FieldStrengthRule, VendorsNominalValuesTakeTheirLawOthersNone)
{
    // What scanners write in (0018,0087): Siemens 1.494 and 2.89362, GE and Philips 1.5 and 3.
    EXPECT_EQ(fieldStrengthOfTesla(1.494), FieldStrength::T1_5);
    EXPECT_EQ(fieldStrengthOfTesla(1.5), FieldStrength::T1_5);
    EXPECT_EQ(fieldStrengthOfTesla(2.89362), FieldStrength::T3);
    EXPECT_EQ(fieldStrengthOfTesla(3.0), FieldStrength::T3);
    // The band's edges, kFieldStrengthToleranceT = 0.25 T either side.
    EXPECT_EQ(fieldStrengthOfTesla(1.75), FieldStrength::T1_5);
    EXPECT_EQ(fieldStrengthOfTesla(2.75), FieldStrength::T3);
    EXPECT_EQ(fieldStrengthOfTesla(3.25), FieldStrength::T3);
    // Other systems get no law: the rule that was here before (3 T from 2.25 T
    // up, else 1.5 T) gave a 7 T scan the 3 T law and a 0.5 T scan the 1.5 T one.
    for (double t : {0.5, 1.0, 1.76, 2.25, 2.74, 3.26, 7.0, 15000.0, -1.5})
        EXPECT_EQ(fieldStrengthOfTesla(t), std::nullopt) << t;
}

TEST(FieldStrengthRule, RecordedWithItsSource)
{
    VolumeMetadata md;
    recordFieldStrength(md, 2.89362, FactSource::Header, FieldStrength::T1_5);
    EXPECT_EQ(md.fieldStrength, FieldStrength::T3);
    EXPECT_EQ(md.fieldStrengthSource, FactSource::Header);
    EXPECT_EQ(md.fieldStrengthTesla, 2.89362);
    // Nothing given: the assumed field, and said so.
    recordFieldStrength(md, std::nullopt, FactSource::Sidecar, FieldStrength::T3);
    EXPECT_EQ(md.fieldStrength, FieldStrength::T3);
    EXPECT_EQ(md.fieldStrengthSource, FactSource::Assumed);
    EXPECT_EQ(md.fieldStrengthTesla, std::nullopt);
    // 7 T: kept as read, with no law.
    recordFieldStrength(md, 7.0, FactSource::Sidecar, FieldStrength::T1_5);
    EXPECT_EQ(md.fieldStrength, std::nullopt);
    EXPECT_EQ(md.fieldStrengthSource, FactSource::Sidecar);
    EXPECT_EQ(md.fieldStrengthTesla, 7.0);
}

/// Metadata with every typed fact set to a value that is not its default.
VolumeMetadata everyFact()
{
    VolumeMetadata md;
    md.modality = "MR";
    md.modalitySource = FactSource::Sidecar;
    md.modalityReason = "Modality MR in the BIDS sidecar x.json";
    md.mrWeighting = MrWeightingKind::T2StarWeighted;
    md.t1Kind = T1Kind::NormalisedWeighted;
    md.fieldStrength = FieldStrength::T3;
    md.fieldStrengthSource = FactSource::Header;
    md.fieldStrengthTesla = 2.8936170212765959; // needs 17 digits to read back
    md.bodyWidthMm = 312.25;
    md.seriesUid = "1.2.3.4";
    md.volumeChoice = VolumeChoice{2, 13, "b=1000"};
    md.phantomLayers = PhantomLayers{Vec3d(0.1, 0, 0), Vec3d(0, -1, 0), {{3, "fat", 2.0, 1.0 / 3.0}}};
    md.landmarks = {{"lesion", Vec3d(1.5, -60.25, 1.0 / 7.0)}, {"entry", Vec3d(0, 0, 0)}};
    return md;
}

TEST(MetadataFacts, EveryFactReadsBackFromItsText)
{
    const VolumeMetadata md = everyFact();
    VolumeMetadata back;
    const auto facts = metadataFacts(md);
    EXPECT_EQ(facts.size(), 15u); // every fact is written: one missing would fail the comparison below too
    for (const auto& [name, text] : facts) EXPECT_TRUE(setMetadataFact(back, name, text, "f")) << name;
    EXPECT_EQ(back, md);
    // A default metadata writes no fact: nothing claimed that nobody said.
    EXPECT_TRUE(metadataFacts(VolumeMetadata{}).empty());
    // Names that are not facts are left to the caller.
    EXPECT_FALSE(setMetadataFact(back, "note", "x", "f"));
    EXPECT_FALSE(setMetadataFact(back, "extra.field_strength", "3T", "f"));
}

TEST(MetadataFacts, BadValuesAreRefusedNamingTheFileAndFact)
{
    VolumeMetadata md;
    const auto refused = [&md](const char* name, const char* text) {
        try {
            setMetadataFact(md, name, text, "scan.vdb");
            return std::string("accepted");
        } catch (const ValueError& e) {
            return std::string(e.what());
        }
    };
    for (const auto& [name, text] :
        std::vector<std::pair<const char*, const char*>>{{"field_strength", "7T"}, {"field_strength_source", "scanner"},
            {"field_strength_tesla", "3 T"}, {"body_width_mm", "nan"}, {"mr_weighting", "T1"}, {"t1_kind", "map"},
            {"volume", "0"}, {"volume_count", "x"}, {"layers", "{"}, {"layers", "{\"entry\": [0, 0, 0]}"},
            {"landmarks", "[1, 2]"}, {"landmarks", "{\"a\": [1, 2]}"}, {"modality_source", ""}}) {
        const std::string msg = refused(name, text);
        EXPECT_EQ(msg.rfind("scan.vdb: metadata '" + std::string(name) + "'", 0), 0u) << name << ": " << msg;
    }
}

TEST(MetadataFacts, FactsWrittenAsExtrasBeforeTheyWereTypedAreRead)
{
    // The display notes a DICOM MR load left in a file before the facts were
    // typed, and the keys a phantom wrote.
    VolumeMetadata md;
    md.extra = {{"modality_source", "Modality MR in the BIDS sidecar t1.json"},
        {"t1_kind", "T1-weighted, normalised per scan"}, {"t1_norm_field", "3T"},
        {"t1_norm_field_source", "MagneticFieldStrength of the headers"}, {"body_width_mm", "312"},
        {"series_uid", "1.2.3"}, {"volume", "2 of 13 (b=1000)"}, {"mr_background", "kept"},
        {"landmarks", "{\"lesion\": [1, 2, 3]}"}};
    upgradeLegacyExtras(md, "old.vdb");
    EXPECT_EQ(md.modalitySource, FactSource::Sidecar);
    EXPECT_EQ(md.modalityReason, "Modality MR in the BIDS sidecar t1.json");
    EXPECT_EQ(md.t1Kind, T1Kind::NormalisedWeighted);
    EXPECT_EQ(md.fieldStrength, FieldStrength::T3);
    EXPECT_EQ(md.fieldStrengthSource, FactSource::Header);
    EXPECT_EQ(md.bodyWidthMm, 312.0);
    EXPECT_EQ(md.seriesUid, "1.2.3");
    EXPECT_EQ(md.volumeChoice, (VolumeChoice{2, 13, "b=1000"}));
    EXPECT_EQ(md.landmarks.at("lesion"), Vec3d(1, 2, 3));
    // The facts leave the notes; the notes stay.
    EXPECT_EQ(md.extra, (std::map<std::string, std::string>{{"mr_background", "kept"}}));

    // A phantom's own key, and the assumed field of a loader whose headers were silent.
    VolumeMetadata phantom;
    phantom.extra = {{"field_strength", "3T"}};
    upgradeLegacyExtras(phantom, "old.vdb");
    EXPECT_EQ(phantom.fieldStrength, FieldStrength::T3);
    EXPECT_EQ(phantom.fieldStrengthSource, FactSource::Generator);
    VolumeMetadata assumed;
    assumed.extra = {{"field_strength_source", "assumed: (0018,0087) MagneticFieldStrength absent"}};
    upgradeLegacyExtras(assumed, "old.vdb");
    EXPECT_EQ(assumed.fieldStrength, FieldStrength::T1_5);
    EXPECT_EQ(assumed.fieldStrengthSource, FactSource::Assumed);

    VolumeMetadata bad;
    bad.extra = {{"volume", "the second"}};
    EXPECT_THROW(upgradeLegacyExtras(bad, "old.vdb"), ValueError);
}

} // namespace
} // namespace voxhap::volume
