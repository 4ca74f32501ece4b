// SPDX-License-Identifier: Apache-2.0
/// @file TestDicomSeries.cpp
/// @brief DICOM series written here with GDCM: ordering by position (never by
/// file name), per-slice rescale, geometry, irregular stacks (missing slice,
/// uneven step, tilt) refused or resampled, series choice, bad files.

#include "common/DicomNative.h"
#include "common/DicomWriter.h"
#include "common/TempDirTest.h"
#include "common/Tolerances.h"

#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/dicom/DicomSeries.h"
#include "volume/mr/T1Normalisation.h"

#include <Eigen/Geometry>
#include <gdcmImageChangeTransferSyntax.h>
#include <gdcmImageReader.h>
#include <gdcmImageWriter.h>
#include <gdcmSequenceOfItems.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <numeric>
#include <random>
#include <tuple>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using voxhap::Vec3d;
using voxhap::test::SyntheticSlice;
using namespace voxhap::volume;

using voxhap::test::kDicomDecimalMm;
/// Resampled values of a field linear in world space: bilinear and linear
/// interpolation reproduce it, up to float rounding of values of order 1e3
/// (ulp ~1e-4) accumulated over a few multiply-adds.
constexpr double kLinearResampleHu = 1e-2;

/// The stored value the synthetic slices hold at column i, row j of slice k.
/// Column 0 is air (0 → HU = intercept, far below the air threshold).
std::int16_t storedValue(int i, int j, int k)
{
    return i == 0 ? std::int16_t(0) : std::int16_t(900 + 7 * i + 13 * j + 31 * k);
}

class DicomSeries : public voxhap::test::TempDirTest {
protected:
    /// A slice k of the standard series at position base + k·step·normal.
    static SyntheticSlice slice(int k, double step = 2.5)
    {
        SyntheticSlice s;
        s.position = Vec3d(-20.0, -30.0, 10.0) + k * step * Vec3d::UnitZ();
        // Per-slice rescale, as scanners may write: the reader must apply each slice's own.
        s.slope = 1.0 + (k % 2);
        s.intercept = -1024.0 + 3 * k;
        s.pixels.resize(std::size_t(s.rows * s.columns));
        for (int j = 0; j < s.rows; ++j)
            for (int i = 0; i < s.columns; ++i) s.pixels[std::size_t(j * s.columns + i)] = storedValue(i, j, k);
        return s;
    }
    /// Write @p slices under names in a shuffled order (file name order ≠ position order).
    void writeShuffled(const std::vector<SyntheticSlice>& slices, const std::string& prefix = "img")
    {
        std::vector<int> names(slices.size());
        std::iota(names.begin(), names.end(), 0);
        std::mt19937 rng(12345);
        std::shuffle(names.begin(), names.end(), rng);
        for (std::size_t n = 0; n < slices.size(); ++n) {
            voxhap::test::writeSyntheticSlice(slices[n], mDir / (prefix + std::to_string(100 + names[n]) + ".dcm"));
        }
    }
};

TEST_F(DicomSeries, ShuffledFilesLoadInPositionOrderWithPerSliceRescale)
{
    std::vector<SyntheticSlice> slices;
    for (int k = 0; k < 10; ++k) slices.push_back(slice(k));
    writeShuffled(slices);

    DicomLoadReport report;
    const Volume v = loadDicom({mDir}, {}, &report);
    const auto box = v.indexBox();
    EXPECT_EQ(box.dims(), voxhap::Vec3i(16, 12, 10));
    const Geometry g = v.geometry();
    EXPECT_TRUE(voxhap::test::nearVec(g.spacing, Vec3d(0.5, 0.75, 2.5), kDicomDecimalMm));
    EXPECT_TRUE(voxhap::test::nearVec(g.origin, slices[0].position, kDicomDecimalMm));
    ASSERT_TRUE(v.has(Channel::Hu));
    EXPECT_EQ(v.metadata().modality, "CT");

    const auto grid = huGrid(v);
    auto acc = grid->getConstAccessor();
    std::int64_t active = 0;
    for (int k = 0; k < 10; ++k) {
        for (int j = 0; j < 12; ++j) {
            for (int i = 0; i < 16; ++i) {
                const double hu =
                    slices[std::size_t(k)].slope * storedValue(i, j, k) + slices[std::size_t(k)].intercept;
                const openvdb::Coord c(i, j, k);
                if (hu < -950.0) {
                    EXPECT_FALSE(acc.isValueOn(c)) << i << "," << j << "," << k;
                    EXPECT_EQ(acc.getValue(c), kAirHu);
                } else {
                    ++active;
                    ASSERT_TRUE(acc.isValueOn(c)) << i << "," << j << "," << k;
                    ASSERT_EQ(acc.getValue(c), float(hu)) << i << "," << j << "," << k; // exact
                }
            }
        }
    }
    EXPECT_EQ(report.activeVoxels, active);
    EXPECT_EQ(report.denseVoxels, 16 * 12 * 10);
    EXPECT_GT(report.memoryBytes, 0u);
}

TEST_F(DicomSeries, MultiFrameFileLoadsEveryFrameAtItsPosition)
{
    std::vector<SyntheticSlice> frames;
    for (int k = 0; k < 5; ++k) {
        SyntheticSlice s = slice(k);
        s.slope = 1.0; // one rescale for the whole file (shared functional group)
        s.intercept = -1024.0;
        frames.push_back(s);
    }
    voxhap::test::writeSyntheticMultiFrame(frames, 2.5, mDir / "enhanced.dcm");
    const Volume v = loadDicom({mDir});
    EXPECT_EQ(v.indexBox().dims(), voxhap::Vec3i(16, 12, 5));
    EXPECT_TRUE(voxhap::test::nearVec(v.geometry().spacing, Vec3d(0.5, 0.75, 2.5), kDicomDecimalMm));
    EXPECT_TRUE(voxhap::test::nearVec(v.indexToWorld(Vec3d(0, 0, 4)), frames[4].position, kDicomDecimalMm));
    auto acc = huGrid(v)->getConstAccessor();
    for (int k = 0; k < 5; ++k) {
        for (int i = 1; i < 16; i += 4)
            EXPECT_EQ(acc.getValue(openvdb::Coord(i, 7, k)), float(storedValue(i, 7, k) - 1024)) << i << "," << k;
    }
}

/// @brief Apply @p edit to the first item of every functional group of an
/// enhanced file (shared, then each frame's), writing the result back.
template <typename Edit> void editFunctionalGroups(const fs::path& file, Edit&& edit)
{
    voxhap::test::rewrite(file, [&](gdcm::File& f) {
        gdcm::DataSet& ds = f.GetDataSet();
        int group = 0;
        for (const gdcm::Tag& tag : {gdcm::Tag(0x5200, 0x9229), gdcm::Tag(0x5200, 0x9230)}) {
            if (!ds.FindDataElement(tag)) continue;
            gdcm::DataElement de = ds.GetDataElement(tag);
            gdcm::SmartPointer<gdcm::SequenceOfItems> sq = de.GetValueAsSQ();
            for (gdcm::SequenceOfItems::SizeType i = 1; i <= sq->GetNumberOfItems(); ++i) {
                edit(sq->GetItem(i).GetNestedDataSet(), group++);
            }
            de.SetValue(*sq);
            ds.Replace(de);
        }
        ds.Remove(gdcm::Tag(0x0020, 0x0037));
    });
}

TEST_F(DicomSeries, EnhancedFileWithoutOrientationIsRefusedBeforeGdcmAssertsOnIt)
{
    // A fuzzing finding: GDCM's ImageHelper aborts the process on an enhanced
    // CT whose functional groups lack the plane orientation.
    std::vector<SyntheticSlice> frames;
    for (int k = 0; k < 3; ++k) frames.push_back(slice(k));
    const fs::path file = mDir / "no-orientation.dcm";
    voxhap::test::writeSyntheticMultiFrame(frames, 2.5, file);
    editFunctionalGroups(file, [](gdcm::DataSet& item, int) { item.Remove(gdcm::Tag(0x0020, 0x9116)); });
    try {
        loadDicom({file});
        FAIL() << "an enhanced file without orientation loaded";
    } catch (const voxhap::IoError& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.rfind(file.string() + ": (0020,0037) ImageOrientationPatient", 0), 0u) << msg;
    }
}

TEST_F(DicomSeries, EnhancedFileWithAFrameOfAnotherOrientationIsRefused)
{
    std::vector<SyntheticSlice> frames;
    for (int k = 0; k < 3; ++k) frames.push_back(slice(k));
    const fs::path file = mDir / "tilted-frame.dcm";
    voxhap::test::writeSyntheticMultiFrame(frames, 2.5, file);
    // Group 0 is the shared one; give the last frame's plane position item its
    // own, different orientation (GDCM asserts that it equals the shared one).
    editFunctionalGroups(file, [](gdcm::DataSet& item, int group) {
        if (group != 3 || !item.FindDataElement(gdcm::Tag(0x0020, 0x9113))) return;
        gdcm::DataElement de = item.GetDataElement(gdcm::Tag(0x0020, 0x9113));
        gdcm::SmartPointer<gdcm::SequenceOfItems> sq = de.GetValueAsSQ();
        gdcm::Attribute<0x0020, 0x0037> iop = {{0, 1, 0, 1, 0, 0}};
        sq->GetItem(1).GetNestedDataSet().Replace(iop.GetAsDataElement());
        de.SetValue(*sq);
        item.Replace(de);
    });
    try {
        loadDicom({file});
        FAIL() << "an enhanced file with a differently oriented frame loaded";
    } catch (const voxhap::IoError& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.rfind(file.string() + ": (0020,0037)", 0), 0u) << msg;
        EXPECT_NE(msg.find("frame 3"), std::string::npos) << msg;
    }
}

TEST_F(DicomSeries, ImageElementWithAnotherValueRepresentationIsRefused)
{
    // A fuzzing finding: gdcm::Attribute asserts when ImagePositionPatient is
    // stored with another VR than DS.
    const fs::path file = mDir / "position-as-lo.dcm";
    voxhap::test::writeSyntheticSlice(slice(0), file);
    voxhap::test::rewrite(file, [](gdcm::File& f) {
        gdcm::DataElement de = f.GetDataSet().GetDataElement(gdcm::Tag(0x0020, 0x0032));
        de.SetVR(gdcm::VR::LO);
        f.GetDataSet().Replace(de);
    });
    try {
        loadDicom({file});
        FAIL() << "a position stored as LO loaded";
    } catch (const voxhap::IoError& e) {
        const std::string msg = e.what();
        // The file, the tag, the byte offset of the element, what is wrong.
        EXPECT_EQ(msg.rfind(file.string() + ": (0020,0032) at byte ", 0), 0u) << msg;
        EXPECT_NE(msg.find(": value representation 'LO' where DS is required"), std::string::npos) << msg;
    }
}

TEST_F(DicomSeries, ImagesThatAreNotCtOrMrAreSetAsideByClass)
{
    // GDCM reads other storage classes down paths that assert on what they do
    // not expect (fuzz findings); none of them is a CT or MR volume. They are
    // set aside by the meta header's class before anything else reads them,
    // and a folder that holds nothing else says so.
    const fs::path file = mDir / "ultrasound.dcm";
    voxhap::test::writeSyntheticSlice(slice(0), file);
    voxhap::test::rewrite(file, [](gdcm::File& f) {
        gdcm::Attribute<0x0008, 0x0016> sop;
        sop.SetValue("1.2.840.10008.5.1.4.1.1.6.1"); // Ultrasound Image Storage
        f.GetDataSet().Replace(sop.GetAsDataElement());
        f.GetHeader().Clear(); // the writer rebuilds the meta header from the data set
    });
    const DicomCatalog c = catalogDicom({mDir});
    EXPECT_TRUE(c.series.empty());
    ASSERT_EQ(c.skipped.size(), 1u);
    EXPECT_EQ(c.skipped.front().category, "Ultrasound Image Storage");
    EXPECT_NE(c.skipped.front().reason.find("1.2.840.10008.5.1.4.1.1.6.1"), std::string::npos)
        << c.skipped.front().reason;
    try {
        loadDicom({file});
        FAIL() << "an ultrasound image loaded";
    } catch (const voxhap::IoError& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.rfind(file.string() + ": no DICOM image found (set aside: 1 Ultrasound Image Storage)", 0), 0u)
            << msg;
    }
}

TEST_F(DicomSeries, UncompressedSamplesReadDirectlyEqualGdcmsDecode)
{
    for (int k = 0; k < 3; ++k) voxhap::test::writeSyntheticSlice(slice(k), mDir / ("s" + std::to_string(k) + ".dcm"));
    voxhap::test::expectNativeEqualsGdcm({mDir});
}

TEST_F(DicomSeries, CompressedSeriesLoadExactlyAsUncompressed)
{
    // Lossless syntaxes go through GDCM's codecs in a child process: the
    // values must be those of the uncompressed series, voxel for voxel.
    for (int k = 0; k < 3; ++k) voxhap::test::writeSyntheticSlice(slice(k), mDir / ("s" + std::to_string(k) + ".dcm"));
    const Volume plain = loadDicom({mDir});
    for (const auto ts : {gdcm::TransferSyntax::JPEGLSLossless, gdcm::TransferSyntax::RLELossless,
             gdcm::TransferSyntax::JPEGLosslessProcess14_1}) {
        const fs::path dir = mDir / ("ts" + std::to_string(int(ts)));
        fs::create_directories(dir);
        for (int k = 0; k < 3; ++k) {
            const fs::path from = mDir / ("s" + std::to_string(k) + ".dcm"), to = dir / from.filename();
            gdcm::ImageReader r;
            r.SetFileName(from.string().c_str());
            ASSERT_TRUE(r.Read());
            gdcm::ImageChangeTransferSyntax change;
            change.SetTransferSyntax(gdcm::TransferSyntax(ts));
            change.SetInput(r.GetImage());
            ASSERT_TRUE(change.Change()) << gdcm::TransferSyntax::GetTSString(ts);
            gdcm::ImageWriter w;
            w.SetFile(r.GetFile());
            w.SetImage(change.GetOutput());
            w.SetFileName(to.string().c_str());
            ASSERT_TRUE(w.Write());
        }
        const Volume packed = loadDicom({dir});
        auto a = huGrid(plain)->getConstAccessor();
        auto b = huGrid(packed)->getConstAccessor();
        for (int k = 0; k < 3; ++k) {
            for (int j = 0; j < 12; ++j) {
                for (int i = 0; i < 16; ++i) {
                    const openvdb::Coord c(i, j, k);
                    ASSERT_EQ(a.getValue(c), b.getValue(c)) << gdcm::TransferSyntax::GetTSString(ts) << " at " << c;
                }
            }
        }
    }
}

TEST_F(DicomSeries, CodecAbortInsideGdcmBecomesOneLineAndTheProcessLivesOn)
{
    // A fuzzing finding: a corrupt JPEG stream on which GDCM's JPEG codec
    // asserts. The decode runs in a child process, so this test survives it.
    const fs::path file = mDir / "corrupt-jpeg.dcm";
    fs::copy_file(
        fs::path(VOXHAP_SOURCE_DIR) / "fuzz/regressions/DicomPreflight/jpeg-stream-gdcm-asserts-on.dcm", file);
    try {
        loadDicom({file});
        FAIL() << "a corrupt JPEG stream loaded";
    } catch (const voxhap::IoError& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.rfind(file.string() + ": (7FE0,0010) PixelData: GDCM aborted", 0), 0u) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
}

TEST_F(DicomSeries, ObliqueOrientationBecomesTheTransform)
{
    const Eigen::Matrix3d rot =
        (Eigen::AngleAxisd(0.4, Vec3d::UnitZ()) * Eigen::AngleAxisd(-0.3, Vec3d::UnitX())).toRotationMatrix();
    const Vec3d row = rot.col(0), col = rot.col(1), normal = row.cross(col);
    std::vector<SyntheticSlice> slices;
    for (int k = 0; k < 5; ++k) {
        SyntheticSlice s = slice(k);
        s.rowDirection = row;
        s.columnDirection = col;
        s.position = Vec3d(5, -7, 30) + k * 1.25 * normal;
        slices.push_back(s);
    }
    writeShuffled(slices);
    const Volume v = loadDicom({mDir});
    for (int k : {0, 4}) {
        for (auto [i, j] : {std::pair{0, 0}, std::pair{15, 0}, std::pair{3, 11}}) {
            const Vec3d expected = slices[std::size_t(k)].position + i * 0.5 * row + j * 0.75 * col;
            EXPECT_TRUE(voxhap::test::nearVec(v.indexToWorld(Vec3d(i, j, k)), expected, kDicomDecimalMm))
                << i << "," << j << "," << k;
        }
    }
    EXPECT_GT(v.geometry().direction.determinant(), 0.0) << "index axes must stay right-handed";
}

TEST_F(DicomSeries, MissingSliceIsRefusedOrResampled)
{
    std::vector<SyntheticSlice> slices;
    for (int k = 0; k < 8; ++k) {
        if (k == 4) continue;
        SyntheticSlice s = slice(k);
        s.slope = 1.0; // one rescale, so that HU is linear in k and interpolation is exact
        s.intercept = -1024.0;
        slices.push_back(s);
    }
    writeShuffled(slices);
    try {
        loadDicom({mDir});
        FAIL() << "a series with a missing slice loaded without resampling";
    } catch (const voxhap::IoError& e) {
        EXPECT_NE(std::string(e.what()).find("1 slice(s) missing"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("ImagePositionPatient"), std::string::npos) << e.what();
    }
    DicomOptions o;
    o.irregular = IrregularSlices::Resample;
    DicomLoadReport report;
    const Volume v = loadDicom({mDir}, o, &report);
    EXPECT_TRUE(report.resampled);
    EXPECT_EQ(v.indexBox().dims().z(), 8);
    EXPECT_NE(v.metadata().extra.count("resampled"), 0u);
    auto acc = huGrid(v)->getConstAccessor();
    for (int k : {3, 4, 5}) {
        for (int i = 1; i < 16; i += 5) {
            EXPECT_NEAR(acc.getValue(openvdb::Coord(i, 6, k)), storedValue(i, 6, k) - 1024.0, kLinearResampleHu)
                << i << "," << k;
        }
    }
}

TEST_F(DicomSeries, UnevenStepIsRefused)
{
    std::vector<SyntheticSlice> slices;
    for (int k = 0; k < 4; ++k) slices.push_back(slice(k));
    slices[3].position.z() += 0.8; // a step of 3.3 mm among steps of 2.5 mm
    writeShuffled(slices);
    try {
        loadDicom({mDir});
        FAIL() << "an uneven series loaded without resampling";
    } catch (const voxhap::IoError& e) {
        EXPECT_NE(std::string(e.what()).find("non-uniform slice spacing"), std::string::npos) << e.what();
    }
}

TEST_F(DicomSeries, GantryTiltIsRefusedOrResampled)
{
    // Tilted acquisition: the slices stay axial, but each is shifted along the
    // column direction by step·tan(tilt). The stored values are linear in world
    // y and z, so a correct resampling reproduces them exactly on the new grid.
    // A shift of 0.5 mm per 2 mm step (14 deg) keeps the field below whole at every pixel centre.
    const double step = 2.0, shift = 0.5;
    const double tiltDeg = std::atan(shift / step) * 180.0 / voxhap::kPi;
    const auto field = [](const Vec3d& w) { return 400.0 + 4.0 * w.y() + 5.0 * w.z(); }; // HU
    std::vector<SyntheticSlice> slices;
    for (int k = 0; k < 6; ++k) {
        SyntheticSlice s = slice(k);
        s.slope = 1.0;
        s.intercept = 0.0;
        s.gantryTilt = tiltDeg;
        s.position = Vec3d(-20.0, -30.0 + k * shift, 10.0 + k * step);
        for (int j = 0; j < s.rows; ++j)
            for (int i = 0; i < s.columns; ++i)
                s.pixels[std::size_t(j * s.columns + i)] =
                    std::int16_t(std::lround(field(s.position + Vec3d(i * 0.5, j * 0.75, 0))));
        slices.push_back(s);
    }
    // The stored values are whole numbers: the field must be too at every pixel centre.
    ASSERT_EQ(field(slices[1].position), std::round(field(slices[1].position))) << "choose a shift on the HU grid";
    writeShuffled(slices);
    try {
        loadDicom({mDir});
        FAIL() << "a tilted series loaded without resampling";
    } catch (const voxhap::IoError& e) {
        EXPECT_NE(std::string(e.what()).find("gantry tilt"), std::string::npos) << e.what();
    }
    DicomOptions o;
    o.irregular = IrregularSlices::Resample;
    const Volume v = loadDicom({mDir}, o);
    EXPECT_TRUE(voxhap::test::nearVec(v.geometry().direction.col(2), Vec3d::UnitZ(), kDicomDecimalMm));
    auto acc = huGrid(v)->getConstAccessor();
    for (int k = 0; k < 6; ++k) {
        // Rows that every shifted input slice still covers.
        for (int j = int(std::ceil(k * shift / 0.75)); j < 12; j += 2) {
            const Vec3d w = v.indexToWorld(Vec3d(5, j, k));
            EXPECT_NEAR(acc.getValue(openvdb::Coord(5, j, k)), field(w), kLinearResampleHu) << j << "," << k;
        }
    }
}

TEST_F(DicomSeries, TwoSeriesInOneFolderAreListedAndChosen)
{
    std::vector<SyntheticSlice> big, small;
    for (int k = 0; k < 6; ++k) big.push_back(slice(k));
    for (int k = 0; k < 3; ++k) {
        SyntheticSlice s = slice(k, 5.0);
        s.seriesUid = "1.2.826.0.1.3680043.2.1125.99.2";
        small.push_back(s);
    }
    writeShuffled(big, "a");
    writeShuffled(small, "b");
    const auto all = listDicomSeries({mDir});
    ASSERT_EQ(all.size(), 2u);
    EXPECT_EQ(all[0].uid, big[0].seriesUid) << "largest first";
    EXPECT_EQ(all[0].slices, 6);
    EXPECT_EQ(all[1].slices, 3);

    EXPECT_EQ(loadDicom({mDir}).indexBox().dims().z(), 6) << "default: the largest CT";
    DicomOptions byUid;
    byUid.series = small[0].seriesUid;
    const Volume v = loadDicom({mDir}, byUid);
    EXPECT_EQ(v.indexBox().dims().z(), 3);
    EXPECT_NEAR(v.geometry().spacing.z(), 5.0, kDicomDecimalMm);
    DicomOptions byNumber;
    byNumber.series = "2";
    EXPECT_EQ(loadDicom({mDir}, byNumber).indexBox().dims().z(), 3);
    DicomOptions unknown;
    unknown.series = "9.9.9";
    EXPECT_THROW(loadDicom({mDir}, unknown), voxhap::ValueError);
}

TEST_F(DicomSeries, LargestCtIsPreferredOverALargerMrSeries)
{
    std::vector<SyntheticSlice> mr, ct;
    for (int k = 0; k < 6; ++k) {
        SyntheticSlice s = slice(k);
        s.modality = "MR";
        s.seriesUid = "1.2.826.0.1.3680043.2.1125.99.3";
        mr.push_back(s);
    }
    for (int k = 0; k < 2; ++k) ct.push_back(slice(k));
    writeShuffled(mr, "m");
    writeShuffled(ct, "c");
    const Volume v = loadDicom({mDir});
    EXPECT_EQ(v.metadata().modality, "CT");
    EXPECT_EQ(v.indexBox().dims().z(), 2);
}

TEST_F(DicomSeries, MrFillsT1OnlyWhenItsHeadersSayT1)
{
    const auto plainMr = [] {
        std::vector<SyntheticSlice> out;
        for (int k = 0; k < 3; ++k) {
            SyntheticSlice s = slice(k);
            s.modality = "MR";
            s.slope = 1.0;
            s.intercept = 0.0;
            out.push_back(s);
        }
        return out;
    };
    std::vector<SyntheticSlice> slices = plainMr();
    // No sequence fields and a neutral description: the weighting is
    // unknown, so the values are an intensity grid, never T1.
    writeShuffled(slices);
    const Volume unknown = loadDicom({mDir});
    EXPECT_FALSE(unknown.has(Channel::Hu));
    EXPECT_FALSE(unknown.has(Channel::T1));
    ASSERT_TRUE(unknown.has(Channel::Intensity));
    EXPECT_EQ(unknown.metadata().mrWeighting, voxhap::volume::MrWeightingKind::Unknown);
    EXPECT_EQ(
        intensityGrid(unknown)->getConstAccessor().getValue(openvdb::Coord(3, 2, 1)), float(storedValue(3, 2, 1)));

    // A T2-weighted turbo spin echo: intensity, named as such.
    fs::remove_all(mDir);
    fs::create_directories(mDir);
    for (auto& s : slices) {
        s.scanningSequence = "SE";
        s.sequenceName = "*tse2d1_15";
        s.repetitionTimeMs = 4000;
        s.echoTimeMs = 100;
    }
    writeShuffled(slices);
    const Volume t2 = loadDicom({mDir});
    EXPECT_FALSE(t2.has(Channel::T1));
    EXPECT_EQ(t2.metadata().mrWeighting, voxhap::volume::MrWeightingKind::T2Weighted);

    // A short-TR, short-TE spin echo is T1-weighted: without normalisation it
    // stays intensity (not T1 in ms) and says why.
    fs::remove_all(mDir);
    fs::create_directories(mDir);
    for (auto& s : slices) s.repetitionTimeMs = 500, s.echoTimeMs = 12;
    writeShuffled(slices);
    DicomOptions raw;
    raw.normaliseT1Weighted = false;
    const Volume weighted = loadDicom({mDir}, raw);
    EXPECT_EQ(weighted.metadata().mrWeighting, voxhap::volume::MrWeightingKind::T1Weighted);
    EXPECT_FALSE(weighted.has(Channel::T1));
    EXPECT_EQ(weighted.metadata().extra.at("t1_norm_refused"), "switched off");

    // A T1 map by its description: T1 in ms as stored.
    fs::remove_all(mDir);
    fs::create_directories(mDir);
    slices = plainMr();
    for (auto& s : slices) s.seriesDescription = "T1 map (MOLLI)";
    writeShuffled(slices);
    const Volume map = loadDicom({mDir});
    ASSERT_TRUE(map.has(Channel::T1));
    EXPECT_EQ(map.metadata().t1Kind, T1Kind::Map);
    EXPECT_EQ(map.metadata().t1Units, "ms");
    EXPECT_EQ(t1Grid(map)->getConstAccessor().getValue(openvdb::Coord(3, 2, 1)), float(storedValue(3, 2, 1)));

    // The user's declaration outranks the headers and is recorded.
    fs::remove_all(mDir);
    fs::create_directories(mDir);
    for (auto& s : slices) s.seriesDescription = "synthetic";
    writeShuffled(slices);
    DicomOptions declared;
    declared.t1Weighted = true;
    declared.normaliseT1Weighted = false;
    const Volume d = loadDicom({mDir}, declared);
    EXPECT_EQ(d.metadata().mrWeighting, voxhap::volume::MrWeightingKind::T1Weighted);
    EXPECT_NE(d.metadata().extra.at("mr_weighting_reason").find("--t1-weighted"), std::string::npos);
}

/// A T1-weighted MR series of four regions: background, fat (brightest),
/// muscle and a dark fluid, written at field strength @p tesla (0: absent).
std::vector<SyntheticSlice> fourRegionMr(double tesla)
{
    std::vector<SyntheticSlice> out;
    for (int k = 0; k < 3; ++k) {
        SyntheticSlice s;
        s.modality = "MR";
        s.seriesDescription = "T1 TSE sag";
        s.slope = 1.0;
        s.intercept = 0.0;
        s.fieldStrength = tesla;
        s.position = Vec3d(-20.0, -30.0, 10.0 + 2.5 * k);
        s.pixels.resize(std::size_t(s.rows * s.columns));
        for (int j = 0; j < s.rows; ++j)
            for (int i = 0; i < s.columns; ++i)
                s.pixels[std::size_t(j * s.columns + i)] = i == 0 ? 0 : i <= 5 ? 800 : i <= 11 ? 300 : 100;
        out.push_back(s);
    }
    return out;
}

TEST_F(DicomSeries, T1WeightedIntensityIsNormalisedPerScanFromFatAndMuscle)
{
    // physics.md §5.1/§5.4: fat and muscle of the scan take the table's T1 at
    // its field strength; between them intensity is linear in 1/T1.
    const auto t1At = [](const Volume& v, int i) {
        return double(t1Grid(v)->getConstAccessor().getValue(openvdb::Coord(i, 4, 1)));
    };
    // Float storage of values of order 1e3 ms: relative rounding 6e-8.
    constexpr double kFloatMs = 1e-3;
    for (const auto& [tesla, fatMs, muscleMs] : {std::tuple{1.5, 290.0, 856.0}, std::tuple{3.0, 382.0, 898.0}}) {
        fs::remove_all(mDir);
        fs::create_directories(mDir);
        writeShuffled(fourRegionMr(tesla));
        const Volume v = loadDicom({mDir});
        EXPECT_EQ(v.metadata().t1Units, "ms");
        EXPECT_EQ(v.metadata().t1Kind, T1Kind::NormalisedWeighted);
        EXPECT_EQ(v.metadata().fieldStrength, tesla > 2 ? FieldStrength::T3 : FieldStrength::T1_5);
        EXPECT_EQ(v.metadata().fieldStrengthSource, FactSource::Header);
        EXPECT_EQ(v.metadata().fieldStrengthTesla, tesla);
        EXPECT_NEAR(t1At(v, 3), fatMs, kFloatMs);
        EXPECT_NEAR(t1At(v, 8), muscleMs, kFloatMs);
        // R1 = R1_fat + (s - 800)·(R1_muscle - R1_fat)/(300 - 800), T1 = 1/R1 up to the clamp.
        const auto expected = [&](double s) {
            const double rate = 1 / fatMs + (s - 800.0) * (1 / muscleMs - 1 / fatMs) / (300.0 - 800.0);
            return rate > 1 / kMaxT1Ms ? 1 / rate : kMaxT1Ms;
        };
        EXPECT_NEAR(t1At(v, 14), expected(100), kFloatMs * 5); // the dark fluid
        // The background (stored 0) is air: inactive, not a clamped T1.
        EXPECT_FALSE(t1Grid(v)->getConstAccessor().isValueOn(openvdb::Coord(0, 4, 1)));
    }
    {
        // At 1.5 T the background lies beyond the rate model's zero: the upper clamp.
        const double rate = 1 / 290.0 + (0 - 800.0) * (1 / 856.0 - 1 / 290.0) / (300.0 - 800.0);
        EXPECT_LT(rate, 0.0);
    }
    // No (0018,0087): the assumed field, and the metadata says it was assumed.
    fs::remove_all(mDir);
    fs::create_directories(mDir);
    writeShuffled(fourRegionMr(0.0));
    DicomOptions o;
    o.assumedField = FieldStrength::T3;
    const Volume v = loadDicom({mDir}, o);
    EXPECT_NEAR(t1At(v, 3), 382.0, kFloatMs);
    EXPECT_EQ(v.metadata().fieldStrength, FieldStrength::T3);
    EXPECT_EQ(v.metadata().fieldStrengthSource, FactSource::Assumed);
    EXPECT_EQ(v.metadata().fieldStrengthTesla, std::nullopt);
}

TEST_F(DicomSeries, T1WeightedScanWithoutFatAndMuscleStaysIntensityAndSaysWhy)
{
    std::vector<SyntheticSlice> slices = fourRegionMr(1.5);
    for (auto& s : slices) std::fill(s.pixels.begin(), s.pixels.end(), std::int16_t(500)); // one grey: no classes
    writeShuffled(slices);
    const Volume v = loadDicom({mDir});
    EXPECT_EQ(v.metadata().mrWeighting, voxhap::volume::MrWeightingKind::T1Weighted);
    EXPECT_FALSE(v.has(Channel::T1)); // so the force models will not read it as T1
    ASSERT_TRUE(v.has(Channel::Intensity));
    EXPECT_NE(v.metadata().extra.at("t1_norm_refused").find(mDir.string()), std::string::npos);
    EXPECT_EQ(intensityGrid(v)->getConstAccessor().getValue(openvdb::Coord(3, 4, 1)), 500.0f);
}

TEST_F(DicomSeries, MemoryCapRefusesBeforeLoading)
{
    for (int k = 0; k < 3; ++k) voxhap::test::writeSyntheticSlice(slice(k), mDir / ("s" + std::to_string(k) + ".dcm"));
    DicomOptions o;
    o.memoryCapBytes = 1000; // the 16×12×3 float grid alone is 2304 bytes
    try {
        loadDicom({mDir}, o);
        FAIL() << "the memory cap was not enforced";
    } catch (const voxhap::IoError& e) {
        EXPECT_NE(std::string(e.what()).find("memory cap"), std::string::npos) << e.what();
    }
}

TEST_F(DicomSeries, TruncatedPixelDataNamesTheFileAndField)
{
    for (int k = 0; k < 3; ++k) voxhap::test::writeSyntheticSlice(slice(k), mDir / ("s" + std::to_string(k) + ".dcm"));
    const fs::path victim = mDir / "s1.dcm";
    fs::resize_file(victim, fs::file_size(victim) - 100);
    try {
        loadDicom({mDir});
        FAIL() << "a truncated file loaded";
    } catch (const voxhap::IoError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("s1.dcm"), std::string::npos) << msg;
        EXPECT_NE(msg.find("PixelData"), std::string::npos) << msg;
    }
}

TEST_F(DicomSeries, ItemDelimiterOutsideASequenceIsRefusedBeforeGdcmReadsIt)
{
    // A fuzzing finding: GDCM re-reads the rest of such a file with other
    // lengths (one of 2.4 GB), so the preflight walk must refuse it.
    const fs::path file = mDir / "stray.dcm";
    voxhap::test::writeSyntheticSlice(slice(0), file);
    std::string bytes;
    {
        std::ifstream in(file, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    const std::size_t pixel = bytes.rfind(std::string("\xe0\x7f\x10\x00", 4));
    ASSERT_NE(pixel, std::string::npos);
    bytes.insert(pixel, std::string("\xfe\xff\x0d\xe0\x00\x00\x00\x00", 8));
    std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
    try {
        loadDicom({file});
        FAIL() << "a file with a stray item delimiter loaded";
    } catch (const voxhap::IoError& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.rfind(file.string() + ": (FFFE,E00D)", 0), 0u) << msg;
    }
}

TEST_F(DicomSeries, UnsupportedOrContradictoryTransferSyntaxIsRefused)
{
    for (auto ts : {gdcm::TransferSyntax::MPEG2MainProfile, gdcm::TransferSyntax::JPEG2000Lossless}) {
        fs::remove_all(mDir);
        fs::create_directories(mDir);
        for (int k = 0; k < 3; ++k)
            voxhap::test::writeSyntheticSlice(slice(k), mDir / ("s" + std::to_string(k) + ".dcm"));
        voxhap::test::relabelTransferSyntax(mDir / "s2.dcm", ts);
        try {
            loadDicom({mDir});
            FAIL() << "a file with transfer syntax " << int(ts) << " and plain pixel data loaded";
        } catch (const voxhap::IoError& e) {
            const std::string msg = e.what();
            EXPECT_NE(msg.find("s2.dcm"), std::string::npos) << msg;
            EXPECT_NE(msg.find("(0002,0010) TransferSyntaxUID"), std::string::npos) << msg;
        }
    }
}

TEST_F(DicomSeries, OutOfRangePixelModuleValuesAreRefusedBeforeGdcmDecodes)
{
    // GDCM asserts (aborts the process) on SamplesPerPixel > 4; found by mutating files.
    for (int k = 0; k < 2; ++k) voxhap::test::writeSyntheticSlice(slice(k), mDir / ("s" + std::to_string(k) + ".dcm"));
    gdcm::Reader r;
    r.SetFileName((mDir / "s1.dcm").string().c_str());
    ASSERT_TRUE(r.Read());
    gdcm::Attribute<0x0028, 0x0002> spp;
    spp.SetValue(9);
    r.GetFile().GetDataSet().Replace(spp.GetAsDataElement());
    gdcm::Writer w;
    w.SetFile(r.GetFile());
    w.SetFileName((mDir / "s1.dcm").string().c_str());
    ASSERT_TRUE(w.Write());
    try {
        loadDicom({mDir});
        FAIL() << "SamplesPerPixel 9 loaded";
    } catch (const voxhap::IoError& e) {
        EXPECT_NE(std::string(e.what()).find("s1.dcm: (0028,0002) SamplesPerPixel"), std::string::npos) << e.what();
    }
}

TEST_F(DicomSeries, NonDicomFilesAreSkippedAndAnEmptyFolderIsAnError)
{
    std::ofstream(mDir / "notes.txt") << "not an image\n";
    try {
        listDicomSeries({mDir});
        FAIL() << "a folder without DICOM gave a series";
    } catch (const voxhap::IoError& e) {
        EXPECT_NE(std::string(e.what()).find("no DICOM image"), std::string::npos) << e.what();
    }
    for (int k = 0; k < 2; ++k) voxhap::test::writeSyntheticSlice(slice(k), mDir / ("s" + std::to_string(k) + ".dcm"));
    EXPECT_EQ(loadDicom({mDir}).indexBox().dims().z(), 2);
    EXPECT_TRUE(looksLikeDicom(mDir / "s0.dcm"));
    EXPECT_FALSE(looksLikeDicom(mDir / "notes.txt"));
}

TEST_F(DicomSeries, MixedOrientationAndDuplicatePositionsAreRefused)
{
    std::vector<SyntheticSlice> slices;
    for (int k = 0; k < 3; ++k) slices.push_back(slice(k));
    slices[2].rowDirection = Vec3d(0, 1, 0);
    slices[2].columnDirection = Vec3d(1, 0, 0);
    writeShuffled(slices);
    try {
        loadDicom({mDir});
        FAIL() << "slices of different orientation loaded as one volume";
    } catch (const voxhap::IoError& e) {
        EXPECT_NE(std::string(e.what()).find("ImageOrientationPatient"), std::string::npos) << e.what();
    }

    fs::remove_all(mDir);
    fs::create_directories(mDir);
    slices = {slice(0), slice(1), slice(1)};
    writeShuffled(slices);
    try {
        loadDicom({mDir});
        FAIL() << "two slices at one position loaded";
    } catch (const voxhap::IoError& e) {
        // The repeated position makes two volumes of unequal size: refused, saying so.
        EXPECT_NE(std::string(e.what()).find("repeat unequally (1 to 2 times)"), std::string::npos) << e.what();
    }
}

} // namespace
