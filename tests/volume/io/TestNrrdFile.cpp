// SPDX-License-Identifier: Apache-2.0
/// @file TestNrrdFile.cpp
/// @brief .nrrd: exact round trips with oblique directions (raw and gzip), the
/// header Slicer reads (checked by parsing it here), RAS files converted to
/// LPS, and bad files refused with one message naming the file and field.

#include "common/TempDirTest.h"
#include "common/Tolerances.h"

#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/detail/SparseSlabs.h"
#include "volume/io/NrrdFile.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using voxhap::Vec3d;
using voxhap::Vec3i;
using namespace voxhap::volume;

class Nrrd : public voxhap::test::TempDirTest {
protected:
    /// Value at voxel (i, j, k): varied, with an air corner (i = 0) below the threshold.
    static float value(int i, int j, int k)
    {
        return i == 0 ? -1000.0f : float(-900 + 37 * i + 11 * j - 5 * k) + 0.25f;
    }

    /// A 11 × 9 × 10 volume (not multiples of the 8-voxel leaf) with oblique axes.
    static Volume makeVolume()
    {
        Geometry g;
        g.spacing = Vec3d(0.7, 1.3, 2.5);
        g.origin = Vec3d(-12.5, 40.25, 101.0);
        g.direction = (Eigen::AngleAxisd(0.3, Vec3d::UnitZ()) * Eigen::AngleAxisd(-0.2, Vec3d(1, 1, 0).normalized()))
                          .toRotationMatrix();
        Volume v(g, IndexBox{Vec3i::Zero(), Vec3i(10, 8, 9)});
        SparseSlabs slabs(kAirHu, -950.0f);
        std::vector<float> data(11 * 9 * 10);
        for (int k = 0; k < 10; ++k)
            for (int j = 0; j < 9; ++j)
                for (int i = 0; i < 11; ++i) data[std::size_t((k * 9 + j) * 11 + i)] = value(i, j, k);
        slabs.addSlab(data.data(), 11, 9, 0, 8); // slabs are one leaf (8 slices) thick
        slabs.addSlab(data.data() + 11 * 9 * 8, 11, 9, 8, 2);
        v.setGrid(Channel::Hu, slabs.finish());
        v.metadata().modality = "CT";
        return v;
    }
    void writeText(const fs::path& p, const std::string& header, const std::string& data = {}) const
    {
        std::ofstream out(p, std::ios::binary);
        out << header << data;
    }
    /// Load @p p expecting an IoError whose one-line message names the file and contains @p field.
    static void expectRefused(const fs::path& p, const std::string& field, const RasterOptions& o = {})
    {
        voxhap::test::expectRefused<voxhap::IoError>([&](const fs::path& f) { loadNrrd(f, o); }, p, field);
    }
};

TEST_F(Nrrd, RoundTripIsExactWithObliqueDirections)
{
    const Volume v = makeVolume();
    for (NrrdEncoding enc : {NrrdEncoding::Raw, NrrdEncoding::Gzip}) {
        const fs::path p = mDir / (enc == NrrdEncoding::Raw ? "raw.nrrd" : "gz.nrrd");
        saveNrrd(v, Channel::Hu, p, enc);
        const Volume back = loadNrrd(p);
        EXPECT_EQ(back.indexBox(), v.indexBox());
        const Geometry a = v.geometry(), b = back.geometry();
        EXPECT_TRUE(voxhap::test::nearVec(b.origin, a.origin, voxhap::test::kRoundTripMm));
        EXPECT_TRUE(voxhap::test::nearVec(b.spacing, a.spacing, voxhap::test::kGeometryRelative * 10));
        for (int c = 0; c < 3; ++c) {
            EXPECT_TRUE(voxhap::test::nearVec(b.direction.col(c), a.direction.col(c), voxhap::test::kGeometryRelative))
                << c;
        }
        EXPECT_EQ(back.metadata().modality, "CT");
        auto acc = huGrid(back)->getConstAccessor();
        for (int k = 0; k < 10; ++k)
            for (int j = 0; j < 9; ++j)
                for (int i = 0; i < 11; ++i) {
                    const openvdb::Coord c(i, j, k);
                    const float expected = value(i, j, k) < -950.0f ? kAirHu : value(i, j, k);
                    ASSERT_EQ(acc.getValue(c), expected) << c; // exact: float bits written and read back
                    EXPECT_EQ(acc.isValueOn(c), expected != kAirHu) << c;
                }
    }
}

TEST_F(Nrrd, TypedFactsAreSavedUnderTheirOwnKeysAndReadBack)
{
    Volume v = makeVolume();
    VolumeMetadata& md = v.metadata();
    md.modalitySource = FactSource::Header;
    md.fieldStrength = FieldStrength::T3;
    md.fieldStrengthSource = FactSource::Sidecar;
    md.fieldStrengthTesla = 2.89362;
    md.seriesUid = "1.2.3";
    md.volumeChoice = VolumeChoice{2, 3, "echo 2 (TE 7.38 ms)"};
    md.landmarks = {{"lesion", Vec3d(1, 2, 3)}};
    md.extra["note"] = "display only: not written";
    const fs::path p = mDir / "facts.nrrd";
    saveNrrd(v, Channel::Hu, p);
    std::string header;
    {
        std::ifstream in(p, std::ios::binary);
        std::getline(in, header, '\0');
        header = header.substr(0, header.find("\n\n") + 1);
    }
    for (const char* line : {"voxhap_field_strength:=3T", "voxhap_field_strength_source:=sidecar",
             "voxhap_field_strength_tesla:=2.89362", "voxhap_series_uid:=1.2.3", "voxhap_volume:=2",
             "voxhap_volume_count:=3", "voxhap_volume_label:=echo 2 (TE 7.38 ms)", "voxhap_modality:=CT",
             R"(voxhap_landmarks:={"lesion":[1.0,2.0,3.0]})"})
        EXPECT_NE(header.find(std::string("\n") + line + "\n"), std::string::npos) << line << " in\n" << header;
    EXPECT_EQ(header.find("note"), std::string::npos);
    const Volume back = loadNrrd(p);
    VolumeMetadata expected = md;
    expected.extra.clear();
    expected.source = "facts.nrrd";
    // The file names its channel hu: CT by the file's own word.
    expected.modalityReason = "declared by the file's voxhap_channel:=hu";
    EXPECT_EQ(back.metadata(), expected);
}

TEST_F(Nrrd, FilesWrittenBeforeTheFactsWereTypedStayReadable)
{
    // voxhap's NRRD header as it was: channel, units, modality and weighting only.
    const fs::path p = mDir / "old.nrrd";
    const std::string data(4 * 2 * 2 * 2, '\0');
    const auto header = [](const std::string& weighting) {
        return "NRRD0004\ntype: float\ndimension: 3\nspace: left-posterior-superior\nsizes: 2 2 2\n"
               "space directions: (1,0,0) (0,1,0) (0,0,1)\nkinds: domain domain domain\nendian: little\n"
               "encoding: raw\nspace origin: (0,0,0)\nvoxhap_channel:=intensity\nvoxhap_units:=arbitrary units\n"
               "voxhap_mr_weighting:=" +
            weighting + "\nvoxhap_modality:=MR\n\n";
    };
    writeText(p, header("T2-weighted"), data);
    const Volume v = loadNrrd(p);
    EXPECT_EQ(v.metadata().modality, "MR");
    EXPECT_EQ(v.metadata().mrWeighting, MrWeightingKind::T2Weighted);
    EXPECT_EQ(v.metadata().fieldStrength, std::nullopt);
    // A value that is not one: refused naming the file and the key.
    writeText(p, header("T3-weighted"), data);
    expectRefused(p, "metadata 'mr_weighting'");
}

TEST_F(Nrrd, GzipStreamIsCheckedToItsEnd)
{
    // A reader that stops once it has its voxels would accept a cut or
    // flipped trailer and bytes after the stream (ByteSource::finish).
    const Volume v = makeVolume();
    const fs::path p = mDir / "gz.nrrd";
    saveNrrd(v, Channel::Hu, p, NrrdEncoding::Gzip);
    std::string bytes;
    {
        std::ifstream in(p, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    const auto write = [&](const std::string& b) { std::ofstream(p, std::ios::binary | std::ios::trunc) << b; };
    write(bytes.substr(0, bytes.size() - 3)); // the length field cut
    expectRefused(p, "trailer");
    std::string flipped = bytes;
    flipped[flipped.size() - 6] = char(flipped[flipped.size() - 6] ^ 0x01); // one CRC-32 bit
    write(flipped);
    expectRefused(p, "data");
    write(bytes + "garbage");
    expectRefused(p, "not another gzip member");
    write(bytes);
    EXPECT_EQ(loadNrrd(p).indexBox(), v.indexBox());
}

TEST_F(Nrrd, HeaderGivesSlicerTheLpsGeometry)
{
    const Volume v = makeVolume();
    const fs::path p = mDir / "v.nrrd";
    saveNrrd(v, Channel::Hu, p, NrrdEncoding::Raw);
    std::ifstream in(p, std::ios::binary);
    std::string line, directions, origin, space;
    while (std::getline(in, line) && !line.empty()) {
        if (line.rfind("space directions: ", 0) == 0) directions = line.substr(18);
        if (line.rfind("space origin: ", 0) == 0) origin = line.substr(14);
        if (line.rfind("space: ", 0) == 0) space = line.substr(7);
    }
    EXPECT_EQ(space, "left-posterior-superior");
    // Parse "(x,y,z) (x,y,z) (x,y,z)" here, independently of the reader.
    const auto parse = [](std::istringstream& s) {
        Vec3d d;
        char c;
        s >> c >> d.x() >> c >> d.y() >> c >> d.z() >> c;
        return d;
    };
    std::istringstream ds(directions), os(origin);
    const Geometry g = v.geometry();
    for (int a = 0; a < 3; ++a) {
        EXPECT_TRUE(voxhap::test::nearVec(parse(ds), g.direction.col(a) * g.spacing[a], voxhap::test::kRoundTripMm))
            << a;
    }
    EXPECT_TRUE(voxhap::test::nearVec(parse(os), v.indexToWorld(Vec3d::Zero()), voxhap::test::kRoundTripMm))
        << "space origin is the centre of voxel (0,0,0)";
    // Raw data: the header plus 11·9·10 floats, nothing more.
    const auto headerBytes = std::size_t(in.tellg());
    EXPECT_EQ(fs::file_size(p), headerBytes + 11 * 9 * 10 * sizeof(float));
}

TEST_F(Nrrd, RasSpaceIsConvertedToLps)
{
    // One axis-aligned 2×1×1 float volume in RAS: +i runs to the patient's
    // right (RAS +x), so in LPS it runs along -x, and the origin's x and y flip.
    const float data[2] = {10.0f, 20.0f};
    writeText(mDir / "ras.nrrd",
        "NRRD0004\ntype: float\ndimension: 3\nspace: right-anterior-superior\nsizes: 2 1 1\n"
        "space directions: (1.5,0,0) (0,2,0) (0,0,3)\nkinds: domain domain domain\nendian: little\n"
        "encoding: raw\nspace origin: (10,20,30)\n\n",
        std::string(reinterpret_cast<const char*>(data), sizeof data));
    const Volume v = loadNrrd(mDir / "ras.nrrd");
    EXPECT_TRUE(voxhap::test::nearVec(v.indexToWorld(Vec3d(0, 0, 0)), Vec3d(-10, -20, 30), voxhap::test::kRoundTripMm));
    EXPECT_TRUE(
        voxhap::test::nearVec(v.indexToWorld(Vec3d(1, 0, 0)), Vec3d(-11.5, -20, 30), voxhap::test::kRoundTripMm));
    EXPECT_EQ(huGrid(v)->getConstAccessor().getValue(openvdb::Coord(1, 0, 0)), 20.0f);
}

TEST_F(Nrrd, BadFilesAreRefusedNamingTheField)
{
    const std::string good = "NRRD0004\ntype: short\ndimension: 3\nspace: left-posterior-superior\nsizes: 4 4 2\n"
                             "space directions: (1,0,0) (0,1,0) (0,0,1)\nendian: little\nencoding: raw\n"
                             "space origin: (0,0,0)\n\n";
    const std::string data(4 * 4 * 2 * 2, '\0');
    const auto with = [&](const std::string& from, const std::string& to) {
        std::string h = good;
        h.replace(h.find(from), from.size(), to);
        return h;
    };
    writeText(mDir / "ok.nrrd", good, data);
    EXPECT_NO_THROW(loadNrrd(mDir / "ok.nrrd"));

    writeText(mDir / "magic.nrrd", "NRRX0004\n" + good.substr(9), data);
    expectRefused(mDir / "magic.nrrd", "magic");
    writeText(mDir / "short.nrrd", good, data.substr(0, data.size() - 3));
    expectRefused(mDir / "short.nrrd", "data");
    writeText(mDir / "noheaderend.nrrd", good.substr(0, 60));
    expectRefused(mDir / "noheaderend.nrrd", "header");
    writeText(mDir / "sizes.nrrd", with("sizes: 4 4 2", "sizes: 4 4"), data);
    expectRefused(mDir / "sizes.nrrd", "sizes");
    writeText(mDir / "type.nrrd", with("type: short", "type: complex"), data);
    expectRefused(mDir / "type.nrrd", "type");
    writeText(mDir / "nospace.nrrd", with("space: left-posterior-superior\n", ""), data);
    expectRefused(mDir / "nospace.nrrd", "space");
    writeText(mDir / "flat.nrrd", with("(0,0,1)", "(1,0,0)"), data);
    expectRefused(mDir / "flat.nrrd", "space directions");
    writeText(mDir / "detached.nrrd", with("encoding: raw\n", "encoding: raw\ndata file: x.raw\n"), data);
    expectRefused(mDir / "detached.nrrd", "data file");
    writeText(mDir / "twice.nrrd", with("encoding: raw\n", "encoding: raw\nencoding: gzip\n"), data);
    expectRefused(mDir / "twice.nrrd", "encoding");
    // Finite but far outside any scanner: OpenVDB's own error must not escape (a fuzzing finding).
    writeText(mDir / "far.nrrd", with("space origin: (0,0,0)", "space origin: (0,0,1e34)"), data);
    expectRefused(mDir / "far.nrrd", "space origin");
    writeText(mDir / "gz.nrrd", with("encoding: raw", "encoding: gzip"), "this is not a gzip stream at all");
    expectRefused(mDir / "gz.nrrd", "data");
}

TEST_F(Nrrd, DimensionsOverTheMemoryCapAreRefusedBeforeReading)
{
    // 100000³ floats would be 4e15 bytes: refused from the header alone (no data follows).
    writeText(mDir / "huge.nrrd",
        "NRRD0004\ntype: float\ndimension: 3\nspace: LPS\nsizes: 100000 100000 100000\n"
        "space directions: (1,0,0) (0,1,0) (0,0,1)\nendian: little\nencoding: raw\n\n");
    expectRefused(mDir / "huge.nrrd", "memory cap");
    RasterOptions small;
    small.memoryCapBytes = 100; // 4×4×2 floats = 128 bytes
    writeText(mDir / "small.nrrd",
        "NRRD0004\ntype: float\ndimension: 3\nspace: LPS\nsizes: 4 4 2\n"
        "space directions: (1,0,0) (0,1,0) (0,0,1)\nendian: little\nencoding: raw\n\n",
        std::string(128, '\0'));
    expectRefused(mDir / "small.nrrd", "memory cap", small);
}

TEST_F(Nrrd, NanVoxelIsRefusedWithItsIndex)
{
    std::vector<float> data(4 * 4 * 2, 0.0f);
    data[4 * 4 + 4 + 2] = std::numeric_limits<float>::quiet_NaN(); // voxel (2, 1, 1)
    writeText(mDir / "nan.nrrd",
        "NRRD0004\ntype: float\ndimension: 3\nspace: LPS\nsizes: 4 4 2\n"
        "space directions: (1,0,0) (0,1,0) (0,0,1)\nendian: little\nencoding: raw\n\n",
        std::string(reinterpret_cast<const char*>(data.data()), data.size() * sizeof(float)));
    expectRefused(mDir / "nan.nrrd", "voxel (2, 1, 1) is not a finite number");
}

} // namespace
