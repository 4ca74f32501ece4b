// SPDX-License-Identifier: Apache-2.0
/// @file TestDicomStoredValues.cpp
/// @brief What the stored bytes and strings say (issue 27 items 2, 4, 5):
/// HighBit, the precision of stored positions, and resampling that keeps
/// every source voxel.

#include "common/DicomWriter.h"
#include "common/TempDirTest.h"

#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/dicom/DicomSeries.h"
#include "volume/dicom/detail/StoredPrecision.h"

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>

namespace {

namespace fs = std::filesystem;
using namespace voxhap::volume;
using voxhap::Vec3d;
using voxhap::test::SyntheticSlice;

/// Replace element @p tag of @p file by the text @p value (a DS or IS string).
void setText(const fs::path& file, gdcm::Tag tag, const gdcm::VR& vr, std::string value)
{
    if (value.size() % 2) value += ' ';
    voxhap::test::rewrite(file, [&](gdcm::File& f) {
        gdcm::DataElement de(tag);
        de.SetVR(vr);
        de.SetByteValue(value.data(), std::uint32_t(value.size()));
        f.GetDataSet().Replace(de);
    });
}

void setUs(const fs::path& file, gdcm::Tag tag, std::uint16_t value)
{
    voxhap::test::rewrite(file, [&](gdcm::File& f) {
        gdcm::DataElement de(tag);
        de.SetVR(gdcm::VR::US);
        de.SetByteValue(reinterpret_cast<const char*>(&value), 2);
        f.GetDataSet().Replace(de);
    });
}

/// "x\y\z" with @p decimals decimals each.
std::string decimals(const Vec3d& p, int decimals)
{
    char buf[96];
    std::snprintf(buf, sizeof buf, "%.*f\\%.*f\\%.*f", decimals, p.x(), decimals, p.y(), decimals, p.z());
    return buf;
}

class DicomStoredValues : public voxhap::test::TempDirTest { };

TEST_F(DicomStoredValues, LastDigitUnitsAndTolerancesFollowTheStoredDigits)
{
    EXPECT_DOUBLE_EQ(lastDigitUnit("12.5"), 0.1);
    EXPECT_DOUBLE_EQ(lastDigitUnit(" -99.65877292014 "), 1e-11);
    EXPECT_DOUBLE_EQ(lastDigitUnit("9.0584602e-009"), 1e-16);
    EXPECT_EQ(lastDigitUnit("-130"), 0.0); // a whole number is exact
    EXPECT_EQ(lastDigitUnit("abc"), 0.0);
    EXPECT_DOUBLE_EQ(finestUnit("-81.599998474121\\-130\\130"), 1e-12);
    EXPECT_DOUBLE_EQ(finestUnit("-20.1\\-30.4\\12"), 0.1);
    // Two coordinates each off by half a unit, projected on a unit vector: √3·unit, plus the floor.
    EXPECT_NEAR(positionToleranceMm(0.1), std::sqrt(3.0) * 0.1 + kPositionFloorMm, 1e-15);
    EXPECT_DOUBLE_EQ(directionTolerance(1e-8), kDirectionFloor);
    EXPECT_NEAR(directionTolerance(1e-3), std::sqrt(3.0) * 1e-3, 1e-15);
}

TEST_F(DicomStoredValues, PositionsStoredToATenthOfAMillimetreMakeNoTilt)
{
    // An oblique MR stack (rotated 17° about x), positions written with one
    // decimal: each coordinate is off by up to 0.05 mm, so the positions
    // drift up to 0.07 mm off the normal line and the steps vary by 0.1 mm.
    // That is rounding, not a tilt and not an uneven stack.
    const double a = 17.0 * voxhap::kPi / 180.0;
    const Vec3d row(1, 0, 0), col(0, std::cos(a), -std::sin(a));
    const Vec3d normal = row.cross(col);
    const double step = 3.3;
    for (int k = 0; k < 20; ++k) {
        SyntheticSlice s;
        s.modality = "MR";
        s.slope = 1.0;
        s.intercept = 0.0;
        s.rowDirection = row;
        s.columnDirection = col;
        s.position = Vec3d(-12.34, -56.78, 9.01) + k * step * normal;
        s.pixels.assign(std::size_t(s.rows * s.columns), std::int16_t(100 + k));
        const fs::path file = mDir / ("s" + std::to_string(k) + ".dcm");
        voxhap::test::writeSyntheticSlice(s, file);
        setText(file, gdcm::Tag(0x0020, 0x0032), gdcm::VR::DS, decimals(s.position, 1));
    }
    DicomOptions o;
    o.removeMrBackground = false;
    DicomLoadReport report;
    const Volume v = loadDicom({mDir}, o, &report);
    EXPECT_FALSE(report.resampled) << report.irregularity;
    EXPECT_EQ(v.indexBox().dims().z(), 20);
    // The step from the rounded positions: within one rounding of the true one.
    EXPECT_NEAR(v.geometry().spacing.z(), step, std::sqrt(3.0) * 0.1);

    // A real gap is still a gap, and the refusal names the option that loads it.
    fs::remove(mDir / "s7.dcm");
    try {
        loadDicom({mDir}, o);
        FAIL() << "a gapped stack loaded without --resample";
    } catch (const voxhap::IoError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("missing"), std::string::npos) << msg;
        EXPECT_NE(msg.find("--resample"), std::string::npos) << msg;
    }
}

TEST_F(DicomStoredValues, ResamplingATiltedStackKeepsEverySourceVoxel)
{
    // A 16.5° gantry tilt: each axial slice is shifted along the column
    // direction by step·tan(tilt). The resampled grid must hold every source
    // voxel centre (checked here voxel by voxel, not from the loader's count).
    const double tilt = 16.5 * voxhap::kPi / 180.0, step = 2.0, dy = 0.75, dx = 0.5;
    const int n = 12;
    std::vector<Vec3d> origins;
    for (int k = 0; k < n; ++k) {
        SyntheticSlice s;
        s.slope = 1.0;
        s.intercept = 0.0;
        s.gantryTilt = 16.5;
        s.position = Vec3d(-20.0, -30.0 + k * step * std::tan(tilt), 10.0 + k * step);
        s.pixels.assign(std::size_t(s.rows * s.columns), std::int16_t(200));
        origins.push_back(s.position);
        voxhap::test::writeSyntheticSlice(s, mDir / ("t" + std::to_string(k) + ".dcm"));
    }
    DicomOptions o;
    o.irregular = IrregularSlices::Resample;
    DicomLoadReport report;
    const Volume v = loadDicom({mDir}, o, &report);
    ASSERT_TRUE(report.resampled);
    EXPECT_EQ(report.sourceVoxelsOutside, 0);
    EXPECT_FALSE(report.interpolation.empty());
    const auto box = v.indexBox();
    std::int64_t outside = 0;
    for (const Vec3d& p0 : origins) {
        for (int j = 0; j < 12; ++j) {
            for (int i = 0; i < 16; ++i) {
                const Vec3d ijk = v.worldToIndex(p0 + Vec3d(i * dx, j * dy, 0));
                // Inside the grid: within half a voxel of its extent (1e-9: float noise of the transform).
                const bool in = (ijk.array() >= box.min.cast<double>().array() - 0.5 - 1e-9).all() &&
                    (ijk.array() <= box.max.cast<double>().array() + 0.5 + 1e-9).all();
                outside += in ? 0 : 1;
            }
        }
    }
    EXPECT_EQ(outside, 0);
    // The shift over the stack, 11 steps · 2 mm · tan 16.5° = 6.5 mm, is 8.7 rows: the grid grew by that.
    EXPECT_EQ(box.dims().y(), 12 + int(std::round((n - 1) * step * std::tan(tilt) / dy)));
    // Every source voxel is 200 HU; the grid's voxels inside the swept region are too.
    auto acc = huGrid(v)->getConstAccessor();
    EXPECT_NEAR(acc.getValue(openvdb::Coord(8, 6, 0)), 200.0f, 1e-3);
    EXPECT_NEAR(acc.getValue(openvdb::Coord(8, box.max.y() - 3, n - 1)), 200.0f, 1e-3);
}

TEST_F(DicomStoredValues, OneImageStoredThreeWaysGivesOneVolume)
{
    // A 12-bit image (values 0..4095): (a) unsigned in the low bits, (b) with
    // garbage in the four high bits, (c) shifted into the high bits
    // (HighBit 15), and (d) signed 12-bit holding the same values minus 2048
    // with a rescale intercept of 2048. PS3.5 §8.1.1: the value sits in bits
    // HighBit − BitsStored + 1 .. HighBit.
    const auto value = [](int i, int j, int k) { return (37 * i + 251 * j + 1009 * k) % 4096; };
    const auto write = [&](const fs::path& dir, int variant) {
        fs::create_directories(dir);
        for (int k = 0; k < 3; ++k) {
            SyntheticSlice s;
            s.slope = 1.0;
            s.intercept = variant == 3 ? 2048.0 : 0.0;
            s.position = Vec3d(0, 0, 2.0 * k);
            s.pixels.resize(std::size_t(s.rows * s.columns));
            for (int j = 0; j < s.rows; ++j) {
                for (int i = 0; i < s.columns; ++i) {
                    const int v = value(i, j, k);
                    std::uint16_t word = std::uint16_t(v);
                    if (variant == 1) word = std::uint16_t(v | ((i * 7 + j) % 16) << 12);
                    if (variant == 2) word = std::uint16_t(v << 4 | ((i + j) % 16));
                    if (variant == 3) word = std::uint16_t(std::int16_t(v - 2048) & 0x0FFF) | ((i % 16) << 12);
                    s.pixels[std::size_t(j * s.columns + i)] = std::int16_t(word);
                }
            }
            const fs::path file = dir / ("s" + std::to_string(k) + ".dcm");
            voxhap::test::writeSyntheticSlice(s, file);
            setUs(file, gdcm::Tag(0x0028, 0x0101), 12);
            setUs(file, gdcm::Tag(0x0028, 0x0102), variant == 2 ? 15 : 11);
            setUs(file, gdcm::Tag(0x0028, 0x0103), variant == 3 ? 1 : 0);
        }
    };
    for (int variant = 0; variant < 4; ++variant) write(mDir / std::to_string(variant), variant);
    DicomOptions keepAll;
    keepAll.airHu = -1e6f;
    for (int variant = 0; variant < 4; ++variant) {
        const Volume v = loadDicom({mDir / std::to_string(variant)}, keepAll);
        auto acc = huGrid(v)->getConstAccessor();
        for (int k = 0; k < 3; ++k)
            for (int j = 0; j < 12; ++j)
                for (int i = 0; i < 16; ++i)
                    ASSERT_EQ(acc.getValue({i, j, k}), float(value(i, j, k))) << "variant " << variant;
    }
}

} // namespace
