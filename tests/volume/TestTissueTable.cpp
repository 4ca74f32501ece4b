// SPDX-License-Identifier: Apache-2.0
/// @file TestTissueTable.cpp
/// @brief The built-in tissue table against physics.md, and validation errors.

#include "common/Tolerances.h"

#include "core/Errors.h"
#include "volume/TissueTable.h"

#include <filesystem>
#include <fstream>
#include <string>
#include <sys/stat.h>
#include <unistd.h>

namespace voxhap::volume {
namespace {

using test::kUnitConversionRelative;

void expectRel(double actual, double expected)
{
    EXPECT_NEAR(actual, expected, std::abs(expected) * kUnitConversionRelative) << "expected " << expected;
}

TEST(TissueTable, BuiltinHoldsThePhysicsReferenceValues)
{
    const TissueTable& t = TissueTable::builtin();
    // physics.md §3.2 [C-ui] puncture forces and thicknesses.
    expectRel(t.at("skin").punctureForce->value, 6.0372);
    expectRel(t.at("ligamentum_flavum").punctureForce->value, 12.133);
    expectRel(t.at("ligamentum_flavum").thickness->value, 7.4);
    // physics.md §5.4: beta_fat = 3696 N·s/m², beta_muscle = 8152 N·s/m², stored in N·s/mm².
    expectRel(t.at("fat").damping->value, 3696e-6);
    expectRel(t.at("muscle").damping->value, 8152e-6);
    // physics.md §4 [LP] Table I: skin k = 330 N/m = 0.33 N/mm, b = 2.1 N·s/m², C = 0.3 N.
    expectRel(t.at("skin").elasticity->value, 0.330);
    expectRel(t.at("skin").frictionViscous->value, 2.1e-6);
    expectRel(t.at("skin").frictionCoulomb->value, 0.3);
    // physics.md §5.1 T1 in ms.
    EXPECT_EQ(t.at("fat").t1(FieldStrength::T1_5), 290.0);
    EXPECT_EQ(t.at("fat").t1(FieldStrength::T3), 382.0);
    EXPECT_EQ(t.at("csf").t1(FieldStrength::T1_5), 4280.0);
    // physics.md §2.3 [S19] Fig. 3 cutting forces.
    expectRel(t.at("interspinous_ligament").cuttingForce->value, 4.0);
    // physics.md §1.1: lung and kidney are the [K01] safety labels.
    EXPECT_TRUE(t.at("lung").critical);
    EXPECT_TRUE(t.at("kidney").critical);
    EXPECT_FALSE(t.at("fat").critical);
}

TEST(TissueTable, BuiltinIsConsistent)
{
    const TissueTable& t = TissueTable::builtin();
    ASSERT_NE(t.find(0), nullptr);
    EXPECT_EQ(t.find(0)->name, "air");
    EXPECT_EQ(t.find(0)->huTypical, -1000.0);
    for (const Tissue& tissue : t.tissues()) {
        EXPECT_EQ(t.find(tissue.id), &tissue);
        EXPECT_EQ(t.find(tissue.name), &tissue);
        EXPECT_LE(tissue.huMin, tissue.huTypical) << tissue.name;
        EXPECT_LE(tissue.huTypical, tissue.huMax) << tissue.name;
        EXPECT_FALSE(tissue.huSource.empty()) << tissue.name;
        if (tissue.id != 0) {
            EXPECT_GT(tissue.t1(FieldStrength::T1_5), 0.0) << tissue.name;
        }
    }
    EXPECT_THROW(t.at("no_such_tissue"), ValueError);
    EXPECT_THROW(t.at(999), ValueError);
}

// A minimal valid table with air and one tissue; each test breaks one thing.
std::string table(
    const std::string& fatExtra, const std::string& fatThickness = R"({"value": 2.8, "unit": "mm", "source": "s"})")
{
    return R"({"schema": "voxhap.tissues/1", "tissues": [
      {"id": 0, "name": "air", "colour": [0,0,0],
       "hu": {"min": -1100, "typical": -1000, "max": -950, "unit": "HU", "source": "s"},
       "t1_1.5T": {"value": 0, "unit": "ms", "source": "s"}, "t1_3T": {"value": 0, "unit": "ms", "source": "s"}},
      {"id": 2, "name": "fat", "colour": [250,220,120],
       "hu": {"min": -190, "typical": -100, "max": -30, "unit": "HU", "source": "s"},
       "t1_1.5T": {"value": 290, "unit": "ms", "source": "s"}, "t1_3T": {"value": 382, "unit": "ms", "source": "s"},
       "thickness": )" +
        fatThickness + fatExtra + R"(}]})";
}

/// Parsing must fail with a ValueError whose message names the file, the entry and the fault.
void expectRejected(const std::string& json, const std::vector<std::string>& fragments)
{
    try {
        TissueTable::parse(json, "test-tissues.json");
        ADD_FAILURE() << "accepted a table that should be rejected";
    } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("test-tissues.json"), std::string::npos) << msg;
        for (const auto& f : fragments) EXPECT_NE(msg.find(f), std::string::npos) << "'" << f << "' not in: " << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << "message must be one line: " << msg;
    }
}

TEST(TissueTable, MinimalTableParsesAndConvertsUnits)
{
    const TissueTable t =
        TissueTable::parse(table("", R"({"value": 1.2, "unit": "cm", "source": "s", "chosen": true})"), "x");
    expectRel(t.at("fat").thickness->value, 12.0);
    EXPECT_TRUE(t.at("fat").thickness->chosen);
    EXPECT_EQ(t.maxId(), 2);
    EXPECT_EQ(t.find(1), nullptr);
}

TEST(TissueTable, RejectsUnknownKey)
{
    expectRejected(table(R"(, "thicknes": {"value": 1, "unit": "mm", "source": "s"})"),
        {"tissue 'fat' (id 2)", "unknown key 'thicknes'"});
    expectRejected(table("", R"({"value": 2.8, "unit": "mm", "source": "s", "sorce": "x"})"),
        {"field 'thickness'", "unknown key 'sorce'"});
}

TEST(TissueTable, RejectsMissingUnit)
{
    expectRejected(
        table("", R"({"value": 2.8, "source": "s"})"), {"tissue 'fat'", "field 'thickness'", "missing 'unit'"});
}

TEST(TissueTable, RejectsUnitOfTheWrongKind)
{
    expectRejected(table("", R"({"value": 2.8, "unit": "N", "source": "s"})"), {"field 'thickness'", "unit 'N'"});
}

TEST(TissueTable, RejectsNegativeValue)
{
    expectRejected(table("", R"({"value": -2.8, "unit": "mm", "source": "s"})"), {"tissue 'fat'", "negative"});
}

TEST(TissueTable, RejectsNonFiniteValue)
{
    // JSON has no NaN literal; an overflowing literal is the way a non-finite number arrives.
    expectRejected(
        table("", R"({"value": 1e999, "unit": "mm", "source": "s"})"), {"tissue 'fat'", "1e999", "not finite"});
    expectRejected(
        table("", R"({"value": "NaN", "unit": "mm", "source": "s"})"), {"field 'thickness'", "not a number"});
}

TEST(TissueTable, RejectsMissingSource)
{
    expectRejected(table("", R"({"value": 2.8, "unit": "mm"})"), {"field 'thickness'", "missing 'source'"});
}

TEST(TissueTable, RejectsInconsistentEntries)
{
    expectRejected(
        table(R"(, "colour": [1,2])"), {"tissue 'fat'"}); // duplicate key: the last one wins in JSON, and it is bad
    std::string dup = table("");
    dup.replace(dup.find("\"id\": 2"), 7, "\"id\": 0");
    expectRejected(dup, {"duplicate id 0"});
    std::string noAir = table("");
    noAir.replace(noAir.find("\"name\": \"air\""), 13, "\"name\": \"gas\"");
    expectRejected(noAir, {"'air'"});
    std::string badHu = table("");
    badHu.replace(badHu.find("\"typical\": -100"), 15, "\"typical\": -500");
    expectRejected(badHu, {"field 'hu'", "min <= typical <= max"});
    expectRejected("{\"tissues\": [", {"not valid JSON"});
}

TEST(TissueTable, LoadNamesAMissingFile)
{
    try {
        TissueTable::load("does-not-exist/tissues.json");
        ADD_FAILURE();
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("does-not-exist/tissues.json"), std::string::npos);
    }
}

/// Issue 20 item 4: a FIFO or a device is refused before it is opened, and a
/// file beyond the 16 MiB limit of every text input is refused, in one line.
TEST(TissueTable, LoadRefusesFifosDevicesAndHugeFiles)
{
    const auto refused = [](const std::filesystem::path& p, const std::string& why) {
        try {
            TissueTable::load(p);
            ADD_FAILURE() << p;
        } catch (const IoError& e) {
            const std::string msg = e.what();
            EXPECT_NE(msg.find(p.string()), std::string::npos) << msg;
            EXPECT_NE(msg.find(why), std::string::npos) << msg;
            EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
        }
    };
    refused("/dev/zero", "file type: a character device, not a regular file");
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / ("voxhap-tissues-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    ASSERT_EQ(::mkfifo((dir / "fifo.json").c_str(), 0600), 0);
    refused(dir / "fifo.json", "file type: a FIFO"); // would block for ever if opened
    {
        std::ofstream big(dir / "big.json");
        big << "{\"tissues\": [" << std::string((16u << 20) + 1, ' ');
    }
    refused(dir / "big.json", "size: 16777230 bytes, beyond the 16 MiB limit");
    std::filesystem::remove_all(dir);
}

TEST(TissueTable, ShippedFileEqualsBuiltin)
{
    const TissueTable file = TissueTable::load(VOXHAP_SOURCE_DIR "/data/tissues.json");
    const TissueTable& builtin = TissueTable::builtin();
    ASSERT_EQ(file.tissues().size(), builtin.tissues().size());
    for (std::size_t i = 0; i < file.tissues().size(); ++i) {
        EXPECT_EQ(file.tissues()[i].name, builtin.tissues()[i].name);
        EXPECT_EQ(file.tissues()[i].huTypical, builtin.tissues()[i].huTypical);
    }
}

} // namespace
} // namespace voxhap::volume
