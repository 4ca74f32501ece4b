// SPDX-License-Identifier: Apache-2.0
/// @file TestMetaImageFile.cpp
/// @brief MetaImage files written here by hand (ITK's layout): oblique
/// TransformMatrix in LPS, inline raw and zlib data, a separate .raw file,
/// big-endian samples, and bad headers refused naming the file and field.

#include "common/TempDirTest.h"
#include "common/Tolerances.h"

#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/io/MetaImageFile.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <zlib.h>

#include <fstream>
#include <limits>
#include <sstream>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

namespace {

namespace fs = std::filesystem;
using voxhap::Mat3d;
using voxhap::Vec3d;
using namespace voxhap::volume;

class MetaImage : public voxhap::test::TempDirTest {
protected:
    static constexpr int kNx = 9, kNy = 6, kNz = 5;
    static std::int16_t stored(int i, int j, int k)
    {
        return i == 0 ? std::int16_t(-1000) : std::int16_t(-300 + 41 * i + 17 * j + 3 * k);
    }
    static Mat3d direction() { return Eigen::AngleAxisd(-0.7, Vec3d(3, -1, 2).normalized()).toRotationMatrix(); }

    static std::string samples(bool bigEndian)
    {
        std::string out;
        for (int k = 0; k < kNz; ++k)
            for (int j = 0; j < kNy; ++j)
                for (int i = 0; i < kNx; ++i) {
                    const auto v = std::uint16_t(stored(i, j, k));
                    const char lo = char(v & 0xff), hi = char(v >> 8);
                    out += bigEndian ? std::string{hi, lo} : std::string{lo, hi};
                }
        return out;
    }
    static std::string header(const std::string& extra, const std::string& dataFile = "LOCAL")
    {
        std::ostringstream h;
        h.precision(17);
        const Mat3d d = direction();
        h << "ObjectType = Image\nNDims = 3\nBinaryData = True\n";
        h << "TransformMatrix =";
        for (int a = 0; a < 3; ++a) h << ' ' << d(0, a) << ' ' << d(1, a) << ' ' << d(2, a); // axis a, as ITK writes
        h << "\nOffset = -12.5 30 7.25\nElementSpacing = 0.6 0.9 1.5\nDimSize = " << kNx << ' ' << kNy << ' ' << kNz
          << "\nElementType = MET_SHORT\n"
          << extra << "ElementDataFile = " << dataFile << "\n";
        return h.str();
    }
    void write(const fs::path& p, const std::string& bytes) const { std::ofstream(p, std::ios::binary) << bytes; }

    void expectVolume(const fs::path& p) const
    {
        const Volume v = loadMetaImage(p);
        EXPECT_EQ(v.indexBox().dims(), voxhap::Vec3i(kNx, kNy, kNz));
        const Mat3d d = direction();
        for (const Vec3d& ijk : {Vec3d(0, 0, 0), Vec3d(kNx - 1, 2, 4)}) {
            const Vec3d expected = Vec3d(-12.5, 30, 7.25) + d * Vec3d(0.6, 0.9, 1.5).asDiagonal() * ijk;
            EXPECT_TRUE(voxhap::test::nearVec(v.indexToWorld(ijk), expected, voxhap::test::kRoundTripMm))
                << ijk.transpose();
        }
        auto acc = huGrid(v)->getConstAccessor();
        for (int k = 0; k < kNz; ++k)
            for (int j = 0; j < kNy; ++j)
                for (int i = 0; i < kNx; ++i) {
                    const float e = stored(i, j, k) < -950 ? kAirHu : float(stored(i, j, k));
                    ASSERT_EQ(acc.getValue(openvdb::Coord(i, j, k)), e) << i << "," << j << "," << k;
                }
    }
    /// Load @p p expecting an IoError whose one-line message names the file and contains @p field.
    static void expectRefused(const fs::path& p, const std::string& field, const RasterOptions& o = {})
    {
        voxhap::test::expectRefused<voxhap::IoError>([&](const fs::path& f) { loadMetaImage(f, o); }, p, field);
    }
};

TEST_F(MetaImage, InlineRawDataWithObliqueTransform)
{
    write(mDir / "a.mha", header("BinaryDataByteOrderMSB = False\n") + samples(false));
    expectVolume(mDir / "a.mha");
}

TEST_F(MetaImage, BigEndianSamples)
{
    write(mDir / "b.mha", header("BinaryDataByteOrderMSB = True\n") + samples(true));
    expectVolume(mDir / "b.mha");
}

TEST_F(MetaImage, ZlibCompressedData)
{
    const std::string raw = samples(false);
    uLongf size = compressBound(uLong(raw.size()));
    std::string z(size, '\0');
    ASSERT_EQ(compress2(reinterpret_cast<Bytef*>(z.data()), &size, reinterpret_cast<const Bytef*>(raw.data()),
                  uLong(raw.size()), 6),
        Z_OK);
    z.resize(size);
    write(mDir / "z.mha", header("CompressedData = True\nCompressedDataSize = " + std::to_string(size) + "\n") + z);
    expectVolume(mDir / "z.mha");
}

TEST_F(MetaImage, SeparateDataFile)
{
    write(mDir / "s.mhd", header("", "s.raw"));
    write(mDir / "s.raw", samples(false));
    expectVolume(mDir / "s.mhd");
}

TEST_F(MetaImage, BadFilesAreRefusedNamingTheField)
{
    const std::string data = samples(false);
    write(mDir / "short.mha", header("") + data.substr(0, data.size() - 7));
    expectRefused(mDir / "short.mha", "data");
    write(mDir / "magic.mha", "P6\n3 2\n255\n" + data);
    expectRefused(mDir / "magic.mha", "magic");
    write(mDir / "nodata.mha", "ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\nElementType = MET_SHORT\n");
    expectRefused(mDir / "nodata.mha", "ElementDataFile");
    std::string h = header("");
    write(mDir / "dims.mha", h.replace(h.find("DimSize = 9 6 5"), 15, "DimSize = 9 6") + data);
    expectRefused(mDir / "dims.mha", "DimSize");
    h = header("");
    write(mDir / "type.mha", h.replace(h.find("MET_SHORT"), 9, "MET_RGB") + data);
    expectRefused(mDir / "type.mha", "ElementType");
    h = header("");
    write(mDir / "flat.mha",
        h.replace(h.find("TransformMatrix ="), 17, "TransformMatrix = 1 0 0 1 0 0 0 0 1\nX =") + data);
    expectRefused(mDir / "flat.mha", "TransformMatrix");
    write(mDir / "missing.mhd", header("", "gone.raw"));
    expectRefused(mDir / "missing.mhd", "ElementDataFile");
    write(mDir / "huge.mha",
        "ObjectType = Image\nNDims = 3\nDimSize = 100000 100000 100000\nElementType = MET_FLOAT\n"
        "ElementDataFile = LOCAL\n");
    expectRefused(mDir / "huge.mha", "memory cap");
    std::vector<float> nan(8, 1.0f);
    nan[3] = std::numeric_limits<float>::infinity(); // voxel (1, 1, 0)
    write(mDir / "inf.mha",
        "ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\nElementType = MET_FLOAT\nElementDataFile = LOCAL\n" +
            std::string(reinterpret_cast<const char*>(nan.data()), nan.size() * 4));
    expectRefused(mDir / "inf.mha", "voxel (1, 1, 0) is not a finite number");
}

/// Issue 20 item 3: ElementDataFile names a file of the header's own folder and
/// nothing else, also once symbolic links are resolved; a FIFO or a device is
/// refused before it is opened (a FIFO with no writer would block the open).
TEST_F(MetaImage, DataFileOutsideTheHeaderFolderIsRefused)
{
    const std::string data = samples(false);
    fs::create_directories(mDir / "sub");
    fs::create_directories(mDir / "other");
    write(mDir / "other" / "x.raw", data);
    write(mDir / "sub" / "x.raw", data);
    write(mDir / "in.raw", data);
    for (const std::string& name : std::vector<std::string>{"/etc/passwd", (mDir / "in.raw").string(), "../other/x.raw",
             "sub/x.raw", "..", "sub/../in.raw", "LIST", "x%03d.raw 1 3 1"}) {
        const fs::path hdr = mDir / "h.mhd";
        write(hdr, header("", name));
        expectRefused(hdr, "ElementDataFile");
        try {
            loadMetaImage(hdr);
        } catch (const voxhap::IoError& e) {
            EXPECT_EQ(std::string(e.what()).find("not found"), std::string::npos) << "refused by name: " << e.what();
        }
    }
    // A symbolic link in the folder that leads out of it.
    fs::create_symlink(mDir / "other" / "x.raw", mDir / "escape.raw");
    write(mDir / "link.mhd", header("", "escape.raw"));
    expectRefused(mDir / "link.mhd", "outside the header's own folder");
    fs::create_symlink("/dev/zero", mDir / "zero.raw");
    write(mDir / "zero.mhd", header("", "zero.raw"));
    expectRefused(mDir / "zero.mhd", "outside the header's own folder");
    // A link within the folder is fine.
    fs::create_symlink("in.raw", mDir / "inside.raw");
    write(mDir / "inside.mhd", header("", "inside.raw"));
    expectVolume(mDir / "inside.mhd");
    // A FIFO in the folder: refused without opening it (the test would hang otherwise).
    ASSERT_EQ(::mkfifo((mDir / "fifo.raw").c_str(), 0600), 0);
    write(mDir / "fifo.mhd", header("", "fifo.raw"));
    expectRefused(mDir / "fifo.mhd", "ElementDataFile: 'fifo.raw' is not a regular file");
}

TEST_F(MetaImage, HeaderThatIsNotARegularFileIsRefusedUnopened)
{
    ASSERT_EQ(::mkfifo((mDir / "fifo.mha").c_str(), 0600), 0);
    expectRefused(mDir / "fifo.mha", "file type: a FIFO");
    fs::create_symlink("/dev/zero", mDir / "zero.mha");
    expectRefused(mDir / "zero.mha", "file type: a character device");
}

} // namespace
