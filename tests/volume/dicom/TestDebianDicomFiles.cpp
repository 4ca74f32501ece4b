// SPDX-License-Identifier: Apache-2.0
/// @file TestDebianDicomFiles.cpp
/// @brief Real DICOM files that Debian ships (pydicom's test data, package
/// python3-pydicom, installed by tools/setup.sh): one MR image in eight
/// encodings, a gzip-compressed copy, a truncated copy, and the non-image
/// objects a folder may hold (RT dose, plan and structure set, a structured
/// report, a segmentation, an ECG waveform).

#include "common/Prerequisites.h"
#include "common/TempDirTest.h"

#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/dicom/DicomSeries.h"

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iterator>
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

/// pydicom's pixel array of @p file (Debian's python3-pydicom, an implementation
/// voxhap does not use), written by VOXHAP_PYTHON to @p out as little-endian
/// int16 row by row; empty if it could not.
std::vector<std::int16_t> pydicomPixels(const fs::path& file, const fs::path& out)
{
    const std::string cmd = std::string(VOXHAP_PYTHON) +
        " -c \"import sys, pydicom; a = pydicom.dcmread(sys.argv[1]).pixel_array; "
        "assert a.shape == (64, 64), a.shape; open(sys.argv[2], 'wb').write(a.astype('<i2').tobytes())\" '" +
        file.string() + "' '" + out.string() + "'";
    if (std::system(cmd.c_str()) != 0) return {};
    std::ifstream in(out, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::vector<std::int16_t> px(bytes.size() / 2);
    for (std::size_t k = 0; k < px.size(); ++k)
        px[k] = std::int16_t(std::uint8_t(bytes[2 * k]) | (std::uint8_t(bytes[2 * k + 1]) << 8));
    return px;
}

/// Every lossless encoding of MR_small decodes to pydicom's array of the
/// uncompressed file: row j, column i is voxel (i, j, 0), value for value (no
/// rescale in these files; background removal off). pydicom has no JPEG-LS
/// decoder here, so the reference is its array of the uncompressed MR_small.dcm.
/// The control: the reference read across instead of down (i and j swapped)
/// differs from the decode, so the comparison would see a transposed image.
TEST_F(DebianDicomFiles, OneImageInEveryEncodingGivesPydicomsPixels)
{
    VOXHAP_REQUIRE(fs::is_directory(kFiles), "pydicom's test files (python3-pydicom) at " << kFiles);
    const std::vector<std::int16_t> ref = pydicomPixels(kFiles / "MR_small.dcm", mDir / "reference.raw");
    VOXHAP_REQUIRE(ref.size() == 64u * 64u, "pydicom under " VOXHAP_PYTHON " (python3-pydicom, python3-numpy)");
    const auto values = [](const Volume& v) { return v.has(Channel::Intensity) ? intensityGrid(v) : huGrid(v); };
    // The uncompressed file itself, implicit and explicit VR, big endian, RLE,
    // JPEG-LS, JPEG 2000 lossless, trailing padding (a (FFFC,FFFC) element), and
    // gzip around the whole file.
    int transposed = 0;
    for (const std::string f :
        {"MR_small.dcm", "MR_small_implicit.dcm", "MR_small_bigendian.dcm", "MR_small_expb.dcm", "MR_small_RLE.dcm",
            "MR_small_jpeg_ls_lossless.dcm", "MR_small_jp2klossless.dcm", "MR_small_padded.dcm", "zipMR.gz"}) {
        const Volume v = loadDicom({folder(f, {f})}, keepEveryVoxel());
        ASSERT_FALSE(v.has(Channel::T1)) << f << ": kept as stored intensity, not normalised T1";
        ASSERT_EQ(v.indexBox().dims(), voxhap::Vec3i(64, 64, 1)) << f;
        auto a = values(v)->getConstAccessor();
        for (int j = 0; j < 64; ++j) {
            for (int i = 0; i < 64; ++i) {
                ASSERT_EQ(a.getValue({i, j, 0}), float(ref[std::size_t(j * 64 + i)])) << f << " at " << i << "," << j;
                transposed += a.getValue({i, j, 0}) != float(ref[std::size_t(i * 64 + j)]);
            }
        }
    }
    EXPECT_GT(transposed, 1000) << "the control: a transposed reference must differ";
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
