// SPDX-License-Identifier: Apache-2.0
/// @file TestDebianDicomFiles.cpp
/// @brief Real DICOM files that Debian ships (pydicom's test data, package
/// python3-pydicom, installed by tools/setup.sh): one MR image in eight
/// encodings, a gzip-compressed copy, a truncated copy, and the non-image
/// objects a folder may hold (RT dose, plan and structure set, a structured
/// report, a segmentation, an ECG waveform).

#include "common/Prerequisites.h"
#include "common/TempDirTest.h"

#include "volume/dicom/DicomSeries.h"
#include "core/Errors.h"
#include "volume/Grids.h"

#include <map>

namespace {

namespace fs = std::filesystem;
using namespace voxhap::volume;

const fs::path kFiles = "/usr/lib/python3/dist-packages/pydicom/data/test_files";

class DebianDicomFiles : public voxhap::test::TempDirTest {
protected:
    /// Copy @p names into a folder of their own under mDir.
    fs::path folder(const std::string& name, const std::vector<std::string>& files) const
    {
        const fs::path dir = mDir / name;
        fs::create_directories(dir);
        for (const auto& f : files) fs::copy_file(kFiles / f, dir / f);
        return dir;
    }
    static DicomOptions keepEveryVoxel()
    {
        DicomOptions o;
        o.removeMrBackground = false;
        return o;
    }
};

TEST_F(DebianDicomFiles, OneImageInEveryEncodingGivesTheSameVoxels)
{
    VOXHAP_REQUIRE(fs::is_directory(kFiles), "pydicom's test files (python3-pydicom) at " << kFiles);
    const Volume reference = loadDicom({folder("le", {"MR_small.dcm"})}, keepEveryVoxel());
    ASSERT_TRUE(reference.has(Channel::Intensity) || reference.has(Channel::T1));
    const auto values = [](const Volume& v) { return v.has(Channel::Intensity) ? intensityGrid(v) : t1Grid(v); };
    // Implicit and explicit VR, big endian, RLE, JPEG-LS, JPEG 2000 lossless,
    // trailing padding (a (FFFC,FFFC) element), and gzip around the whole file.
    for (const std::string f :
        {"MR_small_implicit.dcm", "MR_small_bigendian.dcm", "MR_small_expb.dcm", "MR_small_RLE.dcm",
            "MR_small_jpeg_ls_lossless.dcm", "MR_small_jp2klossless.dcm", "MR_small_padded.dcm", "zipMR.gz"}) {
        const Volume v = loadDicom({folder(f, {f})}, keepEveryVoxel());
        ASSERT_EQ(v.indexBox(), reference.indexBox()) << f;
        auto a = values(v)->getConstAccessor(), b = values(reference)->getConstAccessor();
        for (int j = 0; j < 64; ++j)
            for (int i = 0; i < 64; ++i)
                ASSERT_EQ(a.getValue({i, j, 0}), b.getValue({i, j, 0})) << f << " at " << i << "," << j;
    }
}

TEST_F(DebianDicomFiles, AFolderOfEverythingLoadsItsImagesAndSaysWhatItSetAside)
{
    VOXHAP_REQUIRE(fs::is_directory(kFiles), "pydicom's test files (python3-pydicom) at " << kFiles);
    const fs::path dir = folder("mixed",
        {"CT_small.dcm", "MR_small.dcm", "MR_truncated.dcm", "rtdose.dcm", "rtplan.dcm", "rtstruct.dcm", "test-SR.dcm",
            "liver_1frame.dcm", "waveform_ecg.dcm"});
    DicomLoadReport report;
    const Volume ct = loadDicom({dir}, {}, &report);
    EXPECT_EQ(ct.metadata().modality, "CT"); // the default: CT first
    std::map<std::string, int> counts;
    for (const auto& s : report.skipped) ++counts[s.category];
    EXPECT_EQ(counts["RT Dose Storage"], 1);
    EXPECT_EQ(counts["RT Plan Storage"], 1);
    EXPECT_EQ(counts["Comprehensive SR"], 1);
    EXPECT_EQ(counts["Segmentation Storage"], 1);
    EXPECT_EQ(counts["12-lead ECG Waveform Storage"], 1);
    EXPECT_EQ(counts["not DICOM"], 1); // rtstruct.dcm has no Part 10 preamble
    EXPECT_EQ(counts["damaged"], 1);   // MR_truncated.dcm
    // The truncated copy shares MR_small's series: that series is refused,
    // naming the file, the tag and the offset, unless --skip-bad.
    const DicomCatalog c = catalogDicom({dir});
    const auto mr = std::find_if(c.series.begin(), c.series.end(), [](const auto& s) { return s.modality == "MR"; });
    ASSERT_NE(mr, c.series.end());
    EXPECT_EQ(mr->problem.rfind((dir / "MR_truncated.dcm").string() + ": (7FE0,0010) at byte ", 0), 0u) << mr->problem;
    DicomOptions skip = keepEveryVoxel();
    skip.series = mr->uid;
    EXPECT_THROW(loadDicom({dir}, skip), voxhap::IoError);
    skip.skipBad = true;
    const Volume v = loadDicom({dir}, skip, &report);
    EXPECT_EQ(v.indexBox().dims(), voxhap::Vec3i(64, 64, 1));
    ASSERT_EQ(report.skippedBad.size(), 1u);
    EXPECT_EQ(report.skippedBad.front().file.filename(), "MR_truncated.dcm");
}

} // namespace
