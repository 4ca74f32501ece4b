// SPDX-License-Identifier: Apache-2.0
/// @file TestDicomExports.cpp
/// @brief DICOM as users bring it (issue 27 items 1, 3, 9): a CD export with a
/// DICOMDIR and non-image objects, damaged and padded slices, gzip-compressed
/// files, several series in one folder and the choice among them.

#include "common/DicomWriter.h"
#include "common/SharedData.h"
#include "common/TempDirTest.h"

#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/dicom/DicomSeries.h"

#include <gdcmDICOMDIRGenerator.h>
#include <gdcmFileExplicitFilter.h>
#include <gdcmUIDGenerator.h>
#include <zlib.h>

#include <fstream>
#include <set>

namespace {

namespace fs = std::filesystem;
using namespace voxhap::volume;
using voxhap::Vec3d;
using voxhap::Vec3i;
using voxhap::test::SyntheticSlice;

/// Stored value of voxel (i, j) of slice k: distinct everywhere, so that a
/// misplaced or missing slice shows.
std::int16_t storedAt(int i, int j, int k) { return std::int16_t(100 + 3 * i + 17 * j + 101 * k); }

SyntheticSlice ctSlice(int k, const std::string& uid = "1.2.826.0.1.3680043.2.1125.27.1", double step = 2.0)
{
    SyntheticSlice s;
    s.seriesUid = uid;
    s.slope = 1.0;
    s.intercept = 0.0;
    s.position = Vec3d(-20.0, -30.0, 10.0 + k * step);
    s.pixels.resize(std::size_t(s.rows * s.columns));
    for (int j = 0; j < s.rows; ++j)
        for (int i = 0; i < s.columns; ++i) s.pixels[std::size_t(j * s.columns + i)] = storedAt(i, j, k);
    return s;
}

void writeCt(const fs::path& dir, int n, const std::string& uid = "1.2.826.0.1.3680043.2.1125.27.1")
{
    fs::create_directories(dir);
    for (int k = 0; k < n; ++k)
        voxhap::test::writeSyntheticSlice(ctSlice(k, uid), dir / ("s" + std::to_string(k) + ".dcm"));
}

/// Every voxel of @p v against storedAt (slice k at index k).
void expectStored(const Volume& v, int slices)
{
    ASSERT_EQ(v.indexBox().dims(), Vec3i(16, 12, slices));
    auto acc = huGrid(v)->getConstAccessor();
    for (int k = 0; k < slices; ++k)
        for (int j = 0; j < 12; ++j)
            for (int i = 0; i < 16; ++i)
                ASSERT_EQ(acc.getValue(openvdb::Coord(i, j, k)), float(storedAt(i, j, k))) << i << "," << j << "," << k;
}

/// Write @p in gzip-compressed to @p out (one member).
void gzipFile(const fs::path& in, const fs::path& out)
{
    std::ifstream f(in, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    gzFile gz = gzopen(out.string().c_str(), "wb");
    ASSERT_NE(gz, nullptr);
    ASSERT_EQ(gzwrite(gz, bytes.data(), unsigned(bytes.size())), int(bytes.size()));
    gzclose(gz);
}

std::string readAll(const fs::path& p)
{
    std::ifstream f(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

void writeAll(const fs::path& p, const std::string& bytes)
{
    std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
}

class DicomExports : public voxhap::test::TempDirTest { };

TEST_F(DicomExports, CdExportOfTheRealCtLoadsAsTheFolderDoes)
{
    // A CD as a PACS burns it: PT/ST/SE folders with ISO 9660 names, files in
    // explicit VR little endian (the media profiles require it; the shared CT
    // is implicit VR, so the copies are converted as a CD burner does), a
    // DICOMDIR at the top (written by GDCM's generator), a DIRFILE in every
    // folder, and an exam-summary secondary capture beside the images.
    VOXHAP_REQUIRE_DIR(voxhap::test::realCtDir());
    const fs::path cd = mDir / "CD", series = cd / "DICOM" / "PT000000" / "ST000000" / "SE000000";
    fs::create_directories(series);
    std::vector<fs::path> sources;
    for (const auto& e : fs::directory_iterator(voxhap::test::realCtDir())) sources.push_back(e.path());
    std::sort(sources.begin(), sources.end());
    gdcm::Directory::FilenamesType names;
    for (std::size_t n = 0; n < sources.size(); ++n) {
        char name[32];
        std::snprintf(name, sizeof name, "IM%06zu", n);
        gdcm::Reader r;
        r.SetFileName(sources[n].string().c_str());
        ASSERT_TRUE(r.Read()) << sources[n];
        gdcm::FileExplicitFilter explicitVr;
        explicitVr.SetFile(r.GetFile());
        ASSERT_TRUE(explicitVr.Change()) << sources[n];
        r.GetFile().GetHeader().SetDataSetTransferSyntax(gdcm::TransferSyntax::ExplicitVRLittleEndian);
        gdcm::Writer w;
        w.SetFile(r.GetFile());
        w.SetFileName((series / name).string().c_str());
        ASSERT_TRUE(w.Write()) << name;
        names.push_back((series / name).string());
    }
    gdcm::DICOMDIRGenerator generator;
    generator.SetFilenames(names);
    generator.SetRootDirectory(cd.string());
    generator.SetDescriptor("VOXHAP TEST");
    ASSERT_TRUE(generator.Generate()) << "GDCM could not index the CT";
    gdcm::Writer writer;
    writer.SetFile(generator.GetFile());
    writer.SetFileName((cd / "DICOMDIR").string().c_str());
    ASSERT_TRUE(writer.Write());
    for (const fs::path& dir : {cd / "DICOM", cd / "DICOM" / "PT000000", series}) {
        writeAll(dir / "DIRFILE", std::string("\x01\x00\x00\x00proprietary index", 21));
    }
    SyntheticSlice summary = ctSlice(0, "1.2.826.0.1.3680043.2.1125.27.99");
    summary.modality = "OT";
    voxhap::test::writeSyntheticSlice(summary, series / "IM999999");
    voxhap::test::rewrite(series / "IM999999", [](gdcm::File& f) {
        gdcm::Attribute<0x0008, 0x0016> sop;
        sop.SetValue("1.2.840.10008.5.1.4.1.1.7"); // Secondary Capture Image Storage
        f.GetDataSet().Replace(sop.GetAsDataElement());
        f.GetHeader().Clear();
    });

    const DicomCatalog c = catalogDicom({cd});
    ASSERT_EQ(c.series.size(), 1u);
    std::map<std::string, int> counts;
    for (const auto& s : c.skipped) ++counts[s.category];
    EXPECT_EQ(counts["Media Storage Directory (DICOMDIR)"], 1);
    EXPECT_EQ(counts["Secondary Capture Image Storage"], 1);
    EXPECT_EQ(counts["not DICOM"], 3); // the DIRFILEs
    EXPECT_EQ(c.skipped.size(), 5u);

    // The same voxels as the folder the files came from, by every way of naming the series.
    const Volume original = loadDicom({voxhap::test::realCtDir()});
    for (const std::string& choice :
        {std::string(), std::string("#1"), std::string("1"), c.series.front().number, c.series.front().uid}) {
        DicomOptions o;
        o.series = choice;
        DicomLoadReport report;
        const Volume v = loadDicom({cd}, o, &report);
        EXPECT_EQ(report.skipped.size(), 5u);
        ASSERT_EQ(v.indexBox(), original.indexBox()) << choice;
        EXPECT_EQ(huGrid(v)->activeVoxelCount(), huGrid(original)->activeVoxelCount()) << choice;
        auto a = huGrid(v)->getConstAccessor(), b = huGrid(original)->getConstAccessor();
        for (int k = 0; k < original.indexBox().dims().z(); k += 7)
            for (int j = 0; j < 512; j += 13)
                for (int i = 0; i < 512; i += 11) ASSERT_EQ(a.getValue({i, j, k}), b.getValue({i, j, k})) << choice;
    }
}

TEST_F(DicomExports, SeriesAreChosenByIndexUidOrNumberAndAmbiguityIsRefused)
{
    // Three series: SeriesNumber 2 (5 slices), SeriesNumber 3 (3 slices), SeriesNumber 1 (2 slices).
    const std::string a = "1.2.826.0.1.3680043.2.1125.27.10", b = "1.2.826.0.1.3680043.2.1125.27.11",
                      c = "1.2.826.0.1.3680043.2.1125.27.12";
    const auto write = [&](const std::string& uid, int n, const std::string& number) {
        for (int k = 0; k < n; ++k) {
            SyntheticSlice s = ctSlice(k, uid);
            s.seriesNumber = number;
            voxhap::test::writeSyntheticSlice(s, mDir / (number + "-" + std::to_string(k) + ".dcm"));
        }
    };
    write(a, 5, "2");
    write(b, 3, "3");
    write(c, 2, "1");
    const auto all = listDicomSeries({mDir});
    ASSERT_EQ(all.size(), 3u);
    // The table is ordered by SeriesNumber; indices follow it.
    EXPECT_EQ(all[0].uid, c);
    EXPECT_EQ(all[1].uid, a);
    EXPECT_EQ(all[2].uid, b);
    for (std::size_t n = 0; n < 3; ++n) EXPECT_EQ(all[n].index, int(n + 1));

    const auto depth = [&](const std::string& choice) {
        DicomOptions o;
        o.series = choice;
        return loadDicom({mDir}, o).indexBox().dims().z();
    };
    EXPECT_EQ(depth(""), 5);   // the default: the largest loadable (all CT)
    EXPECT_EQ(depth("#1"), 2); // index 1: SeriesNumber 1
    EXPECT_EQ(depth("#3"), 3);
    EXPECT_EQ(depth(b), 3);
    // "1" is index 1 and SeriesNumber 1: the same series, no ambiguity.
    EXPECT_EQ(depth("1"), 2);
    // "2" is index 2 (SeriesNumber 2, series a) and SeriesNumber 2 (a): one series.
    EXPECT_EQ(depth("2"), 5);
    // "3" is index 3 (series b, SeriesNumber 3) and SeriesNumber 3 (b): one series.
    EXPECT_EQ(depth("3"), 3);

    // Renumber: index 2 is a, SeriesNumber 2 becomes c: "2" is ambiguous.
    fs::remove_all(mDir);
    fs::create_directories(mDir);
    write(a, 5, "5");
    write(b, 3, "7");
    write(c, 2, "2");
    try {
        depth("2");
        FAIL() << "an ambiguous --series loaded";
    } catch (const voxhap::ValueError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("ambiguous"), std::string::npos) << msg;
        EXPECT_NE(msg.find(a), std::string::npos) << msg; // both candidates named
        EXPECT_NE(msg.find(c), std::string::npos) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
    EXPECT_EQ(depth("#2"), 5); // the index form is never ambiguous
    EXPECT_THROW(depth("#9"), voxhap::ValueError);
}

TEST_F(DicomExports, DefaultSeriesIsTheLargestLoadableCtThenT1WeightedMr)
{
    // A big 4D MR (two echoes at the same positions), a smaller T1-weighted
    // MR, and a PD-weighted MR larger than the T1-weighted one: the 4D series
    // does not load as one volume, and T1-weighted comes before other MR.
    const auto mr = [&](const std::string& uid, int n, int echoes, double tr, double te, const std::string& number) {
        for (int e = 1; e <= echoes; ++e) {
            for (int k = 0; k < n; ++k) {
                SyntheticSlice s = ctSlice(k, uid);
                s.modality = "MR";
                s.scanningSequence = "SE";
                s.repetitionTimeMs = tr;
                s.echoTimeMs = te * e;
                s.echoNumber = e;
                s.seriesNumber = number;
                voxhap::test::writeSyntheticSlice(
                    s, mDir / (number + "-" + std::to_string(e) + "-" + std::to_string(k) + ".dcm"));
            }
        }
    };
    mr("1.2.826.0.1.3680043.2.1125.27.20", 8, 2, 3000, 15, "4"); // PD and a later echo: 16 files
    mr("1.2.826.0.1.3680043.2.1125.27.21", 3, 1, 500, 12, "5");  // T1-weighted spin echo
    mr("1.2.826.0.1.3680043.2.1125.27.22", 6, 1, 3000, 12, "6"); // PD-weighted
    DicomOptions raw;
    raw.normaliseT1Weighted = false;
    raw.removeMrBackground = false;
    DicomLoadReport report;
    const Volume v = loadDicom({mDir}, raw, &report);
    EXPECT_EQ(report.series.uid, "1.2.826.0.1.3680043.2.1125.27.21");
    EXPECT_EQ(v.metadata().mrWeighting, voxhap::volume::MrWeightingKind::T1Weighted);
    // Add a CT: it comes first whatever its size.
    writeCt(mDir / "ct", 2);
    loadDicom({mDir}, raw, &report);
    EXPECT_EQ(report.series.modality, "CT");
    // The 4D series is listed with its volumes and loads one on request.
    const DicomCatalog c = catalogDicom({mDir});
    const auto& fourD = *std::find_if(c.series.begin(), c.series.end(), [](const auto& s) { return s.number == "4"; });
    EXPECT_EQ(fourD.volumes, 2u);
    EXPECT_NE(fourD.problem.find("--volume 1..2"), std::string::npos) << fourD.problem;
    DicomOptions second = raw;
    second.series = "1.2.826.0.1.3680043.2.1125.27.20"; // "4" is now ambiguous: SeriesNumber 4 and the CT's index 4
    second.volume = 2;
    const Volume echo2 = loadDicom({mDir}, second, &report);
    EXPECT_EQ(report.volume, 2u);
    EXPECT_EQ(echo2.indexBox().dims().z(), 8);
    ASSERT_TRUE(echo2.metadata().volumeChoice);
    EXPECT_EQ(echo2.metadata().volumeChoice->index, 2);
    EXPECT_EQ(echo2.metadata().volumeChoice->count, 2);
    EXPECT_NE(echo2.metadata().volumeChoice->label.find("echo 2"), std::string::npos)
        << echo2.metadata().volumeChoice->label;
}

TEST_F(DicomExports, DamagedSliceIsNamedWithItsOffsetAndSkipBadLoadsTheRest)
{
    writeCt(mDir, 5);
    // Cut the last slice inside its pixel data.
    const fs::path last = mDir / "s4.dcm";
    const auto size = fs::file_size(last);
    fs::resize_file(last, size - 100);
    try {
        loadDicom({mDir});
        FAIL() << "a series with a truncated slice loaded";
    } catch (const voxhap::IoError& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.rfind(last.string() + ": (7FE0,0010) at byte ", 0), 0u) << msg;
        EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;
        EXPECT_NE(msg.find("--skip-bad"), std::string::npos) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
    DicomOptions skip;
    skip.skipBad = true;
    DicomLoadReport report;
    const Volume v = loadDicom({mDir}, skip, &report);
    expectStored(v, 4);
    ASSERT_EQ(report.skippedBad.size(), 1u);
    EXPECT_EQ(report.skippedBad.front().file, last);

    // A damaged slice in the middle leaves a gap: refused, naming --resample, or resampled.
    fs::remove_all(mDir);
    writeCt(mDir, 5);
    const fs::path middle = mDir / "s2.dcm";
    fs::resize_file(middle, fs::file_size(middle) - 100);
    try {
        loadDicom({mDir}, skip);
        FAIL() << "a gap left by a skipped slice loaded";
    } catch (const voxhap::IoError& e) {
        EXPECT_NE(std::string(e.what()).find("--resample"), std::string::npos) << e.what();
    }
    skip.irregular = IrregularSlices::Resample;
    const Volume gap = loadDicom({mDir}, skip, &report);
    EXPECT_EQ(gap.indexBox().dims().z(), 5);
    EXPECT_EQ(report.skippedBad.size(), 1u);
}

TEST_F(DicomExports, TrailingZeroPaddingIsNotCorruptionButOtherTrailingBytesAre)
{
    writeCt(mDir, 4);
    const fs::path padded = mDir / "s1.dcm";
    writeAll(padded, readAll(padded) + std::string(2500000, '\0')); // 2.5 MB of zeros, as an archive wrote them
    DicomLoadReport report;
    expectStored(loadDicom({mDir}, {}, &report), 4);
    EXPECT_EQ(report.paddedFiles, 1);

    // Bytes that are not zero after the last element are refused, at their offset.
    const std::string clean = readAll(mDir / "s2.dcm");
    writeAll(mDir / "s2.dcm", clean + std::string("\x12\x34garbage", 9));
    try {
        loadDicom({mDir});
        FAIL() << "trailing garbage loaded";
    } catch (const voxhap::IoError& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.rfind((mDir / "s2.dcm").string() + ": ", 0), 0u) << msg;
        EXPECT_NE(msg.find("at byte " + std::to_string(clean.size())), std::string::npos) << msg;
    }
}

TEST_F(DicomExports, GzipCompressedFilesLoadAsDicomAndDamagedStreamsAreRefused)
{
    writeCt(mDir / "plain", 4);
    fs::create_directories(mDir / "gz");
    for (int k = 0; k < 4; ++k) {
        gzipFile(
            mDir / "plain" / ("s" + std::to_string(k) + ".dcm"), mDir / "gz" / ("s" + std::to_string(k) + ".dcm.gz"));
    }
    expectStored(loadDicom({mDir / "gz"}), 4);
    // No inflated copy is left behind.
    EXPECT_TRUE(
        std::none_of(fs::directory_iterator(fs::temp_directory_path()), fs::directory_iterator(), [](const auto& e) {
            return e.path().filename().string().rfind("voxhap-dicom-gz-", 0) == 0 && fs::exists(e.path() / "0.dcm") &&
                fs::last_write_time(e.path()) > fs::file_time_type::clock::now() - std::chrono::seconds(60);
        }));

    // One member's trailer cut, then bytes after the last member: each is
    // refused naming the .gz file the user has, never loaded as other voxels.
    const fs::path victim = mDir / "gz" / "s3.dcm.gz";
    const std::string good = readAll(victim);
    for (const std::string& bad : {good.substr(0, good.size() - 4), good + "junk"}) {
        writeAll(victim, bad);
        try {
            loadDicom({mDir / "gz"});
            FAIL() << "a damaged .dcm.gz loaded";
        } catch (const voxhap::IoError& e) {
            const std::string msg = e.what();
            EXPECT_EQ(msg.rfind(victim.string() + ": ", 0), 0u) << msg;
            EXPECT_EQ(msg.find("voxhap-dicom-gz"), std::string::npos) << "names a temporary copy: " << msg;
        }
    }
    // Two members concatenated are one stream (RFC 1952 §2.2).
    const std::string whole = readAll(mDir / "plain" / "s3.dcm");
    writeAll(mDir / "half1", whole.substr(0, 1000));
    writeAll(mDir / "half2", whole.substr(1000));
    gzipFile(mDir / "half1", mDir / "m1.gz");
    gzipFile(mDir / "half2", mDir / "m2.gz");
    writeAll(victim, readAll(mDir / "m1.gz") + readAll(mDir / "m2.gz"));
    expectStored(loadDicom({mDir / "gz"}), 4);
}

TEST_F(DicomExports, NonImageObjectsInASeriesFolderDoNotStopIt)
{
    // Philips and Siemens exports put raw data and reports among the images.
    writeCt(mDir, 3);
    for (const auto& [name, sop] :
        {std::pair{"raw.dcm", "1.2.840.10008.5.1.4.1.1.66"}, std::pair{"sr.dcm", "1.2.840.10008.5.1.4.1.1.88.22"}}) {
        voxhap::test::writeSyntheticSlice(ctSlice(0), mDir / name);
        voxhap::test::rewrite(mDir / name, [sop = std::string(sop)](gdcm::File& f) {
            gdcm::Attribute<0x0008, 0x0016> a;
            a.SetValue(sop);
            f.GetDataSet().Replace(a.GetAsDataElement());
            f.GetHeader().Clear();
        });
    }
    DicomLoadReport report;
    DicomOptions o;
    o.series = "1";
    expectStored(loadDicom({mDir}, o, &report), 3);
    std::set<std::string> categories;
    for (const auto& s : report.skipped) categories.insert(s.category);
    EXPECT_EQ(categories, (std::set<std::string>{"Raw Data Storage", "Enhanced SR"}));
}

} // namespace

namespace {

/// Set, in every per-frame functional group of @p file, the frame's plane
/// position and its temporal position index: frames 0..n-1 at positions
/// z0 + (f mod slices)·step, time point 1 + f / slices.
void makeEnhancedTimeSeries(const fs::path& file, int slices, double z0, double step)
{
    voxhap::test::rewrite(file, [&](gdcm::File& f) {
        gdcm::DataSet& ds = f.GetDataSet();
        gdcm::DataElement perFrame = ds.GetDataElement(gdcm::Tag(0x5200, 0x9230));
        gdcm::SmartPointer<gdcm::SequenceOfItems> sq = perFrame.GetValueAsSQ();
        ASSERT_TRUE(sq);
        for (gdcm::SequenceOfItems::SizeType i = 1; i <= sq->GetNumberOfItems(); ++i) {
            const int frame = int(i) - 1;
            gdcm::DataSet& item = sq->GetItem(i).GetNestedDataSet();
            // (0020,9113) PlanePosition → (0020,0032)
            gdcm::Attribute<0x0020, 0x0032> ipp = {{-20.0, -30.0, z0 + (frame % slices) * step}};
            gdcm::Item positionItem;
            positionItem.GetNestedDataSet().Insert(ipp.GetAsDataElement());
            gdcm::SmartPointer<gdcm::SequenceOfItems> positions = new gdcm::SequenceOfItems;
            positions->AddItem(positionItem);
            gdcm::DataElement pp(gdcm::Tag(0x0020, 0x9113));
            pp.SetVR(gdcm::VR::SQ);
            pp.SetValue(*positions);
            item.Replace(pp);
            // (0020,9111) FrameContent → (0020,9128) TemporalPositionIndex (UL)
            const std::uint32_t t = std::uint32_t(1 + frame / slices);
            gdcm::DataElement index(gdcm::Tag(0x0020, 0x9128));
            index.SetVR(gdcm::VR::UL);
            index.SetByteValue(reinterpret_cast<const char*>(&t), 4);
            gdcm::Item contentItem;
            contentItem.GetNestedDataSet().Insert(index);
            gdcm::SmartPointer<gdcm::SequenceOfItems> content = new gdcm::SequenceOfItems;
            content->AddItem(contentItem);
            gdcm::DataElement fc(gdcm::Tag(0x0020, 0x9111));
            fc.SetVR(gdcm::VR::SQ);
            fc.SetValue(*content);
            item.Replace(fc);
        }
        perFrame.SetValue(*sq);
        ds.Replace(perFrame);
    });
}

TEST_F(DicomExports, EnhancedMultiFrameTimeSeriesLoadsOneTimePoint)
{
    // One enhanced file, 3 slices × 2 time points: the frames repeat
    // positions and differ in TemporalPositionIndex (0020,9128).
    std::vector<SyntheticSlice> frames;
    for (int f = 0; f < 6; ++f) frames.push_back(ctSlice(f)); // values differ by frame
    const fs::path file = mDir / "enhanced.dcm";
    voxhap::test::writeSyntheticMultiFrame(frames, 2.0, file);
    makeEnhancedTimeSeries(file, 3, 10.0, 2.0);
    const DicomCatalog c = catalogDicom({mDir});
    ASSERT_EQ(c.series.size(), 1u);
    EXPECT_EQ(c.series.front().volumes, 2u);
    EXPECT_EQ(c.series.front().separatedBy, "temporal position");
    EXPECT_THROW(loadDicom({mDir}), voxhap::IoError);
    for (std::size_t t = 1; t <= 2; ++t) {
        DicomOptions o;
        o.volume = t;
        const Volume v = loadDicom({mDir}, o);
        ASSERT_EQ(v.indexBox().dims().z(), 3);
        auto acc = huGrid(v)->getConstAccessor();
        // Slice k of time point t is frame 3·(t − 1) + k, whose stored values are storedAt(·, ·, frame).
        for (int k = 0; k < 3; ++k)
            EXPECT_EQ(acc.getValue({5, 4, k}), float(storedAt(5, 4, int(3 * (t - 1)) + k))) << t << "," << k;
        ASSERT_TRUE(v.metadata().volumeChoice);
        EXPECT_NE(v.metadata().volumeChoice->label.find("time point " + std::to_string(t)), std::string::npos);
    }
}

} // namespace

namespace {

TEST_F(DicomExports, ALocalizerInsideACtSeriesIsAVolumeOfItsOwn)
{
    // Some CT exports keep the scout in the series of the axial slices: another
    // image type, another plane. It must neither break the series nor be stacked with it.
    for (int k = 0; k < 5; ++k) {
        SyntheticSlice s = ctSlice(k);
        s.imageType = "ORIGINAL\\PRIMARY\\AXIAL";
        s.instanceNumber = k + 2;
        voxhap::test::writeSyntheticSlice(s, mDir / ("ax" + std::to_string(k) + ".dcm"));
    }
    SyntheticSlice scout = ctSlice(0);
    scout.imageType = "ORIGINAL\\PRIMARY\\LOCALIZER";
    scout.rowDirection = Vec3d(1, 0, 0);
    scout.columnDirection = Vec3d(0, 0, -1); // coronal
    scout.instanceNumber = 1;
    voxhap::test::writeSyntheticSlice(scout, mDir / "a-scout.dcm"); // first in file order
    const DicomCatalog c = catalogDicom({mDir});
    ASSERT_EQ(c.series.size(), 1u);
    EXPECT_EQ(c.series.front().volumes, 2u);
    EXPECT_EQ(c.series.front().separatedBy, "image type");
    EXPECT_NE(c.series.front().problem.find("--volume"), std::string::npos) << c.series.front().problem;
    DicomOptions o;
    o.volume = 2; // the scout was acquired first
    const Volume axial = loadDicom({mDir}, o);
    expectStored(axial, 5);
    o.volume = 1;
    EXPECT_EQ(loadDicom({mDir}, o).indexBox().dims().z(), 1);
}

} // namespace
