// SPDX-License-Identifier: Apache-2.0
/// @file TestCtImageTypes.cpp
/// @brief One CT stack per series whatever ImageType's fourth value says: a
/// series built from the real abdominal CT's files (../shared/data), their
/// headers rewritten like a GE head CT's (half the slices ORIGINAL\PRIMARY\AXIAL\ADD
/// at 3 mm, the rest ORIGINAL\PRIMARY\AXIAL at 6 mm, overlapping at the junction,
/// sheared like a gantry tilt) loads as one volume through --resample, every voxel
/// the source pixels (decoded here by GDCM) placed and interpolated as the
/// documents say. Two reconstructions of one range, a junction overlapping by more
/// than a slice, and the same series as MR stay separate volumes.

#include "common/SharedData.h"
#include "common/TempDirTest.h"

#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/dicom/DicomSeries.h"

#include <gdcmAttribute.h>
#include <gdcmImageReader.h>
#include <gdcmReader.h>
#include <gdcmWriter.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using voxhap::Vec3d;
using namespace voxhap::volume;

/// The real CT's pixel spacing [mm] (its README and headers: 1.07421875 mm, 3 mm slices).
constexpr double kPixelMm = 1.07421875;
/// The shear of the test series: one pixel along the column direction per 1.5 mm
/// along the normal (35.5°), so that every slice below, at a multiple of 1.5 mm,
/// lies a whole number of pixels across and the resampled grid meets its pixels.
constexpr double kShearPerMm = kPixelMm / 1.5;
/// The resampled voxels are float sums of at most four products of float HU: a
/// few ulps of a few thousand HU.
constexpr double kInterpolatedHu = 1e-3;

/// One file of the test series: which source file gives its pixels, where it lies
/// along the normal above the base (0 = the first thin slice), its image type and
/// slice thickness.
struct Planned {
    std::size_t source = 0;
    double along = 0;
    std::string imageType;
    double thicknessMm = 0;
};

class CtImageTypes : public voxhap::test::TempDirTest {
protected:
    void SetUp() override
    {
        TempDirTest::SetUp();
        VOXHAP_REQUIRE_DIR(voxhap::test::realCtDir());
        for (const auto& e : fs::directory_iterator(voxhap::test::realCtDir())) mSources.push_back(e.path());
        std::sort(mSources.begin(), mSources.end());
        ASSERT_GE(mSources.size(), 40u);
        gdcm::Reader r;
        r.SetFileName(mSources.front().string().c_str());
        ASSERT_TRUE(r.Read());
        gdcm::Attribute<0x0020, 0x0032> ipp;
        ipp.SetFromDataSet(r.GetFile().GetDataSet());
        mBase = Vec3d(ipp.GetValue(0), ipp.GetValue(1), ipp.GetValue(2)) - Vec3d(0, 0, 200.0);
    }

    /// 20 thin slices (3 mm, ADD) from the base, then 20 thick ones (6 mm) from
    /// @p thickStart along the normal.
    static std::vector<Planned> thinThenThick(double thickStart, int thick = 20)
    {
        std::vector<Planned> p;
        for (int k = 0; k < 20; ++k) p.push_back({std::size_t(k), 3.0 * k, "ORIGINAL\\PRIMARY\\AXIAL\\ADD", 3.0});
        for (int m = 0; m < thick; ++m)
            p.push_back({std::size_t(20 + m), thickStart + 6.0 * m, "ORIGINAL\\PRIMARY\\AXIAL", 6.0});
        return p;
    }

    /// The real CT's files with their headers rewritten as @p plan says, into @p dir:
    /// position sheared along the column direction (+y) like a gantry tilt,
    /// (0018,1120) GantryDetectorTilt, (0008,0008) ImageType, (0018,0050)
    /// SliceThickness; the pixels untouched.
    void write(const std::vector<Planned>& plan, const fs::path& dir, const std::string& modality = "CT") const
    {
        fs::create_directories(dir);
        const double tiltDeg = std::atan(kShearPerMm) * 180.0 / voxhap::kPi;
        for (const Planned& p : plan) {
            gdcm::Reader r;
            r.SetFileName(mSources[p.source].string().c_str());
            ASSERT_TRUE(r.Read()) << mSources[p.source];
            gdcm::DataSet& ds = r.GetFile().GetDataSet();
            const Vec3d at = position(p.along);
            gdcm::Attribute<0x0020, 0x0032> ipp = {{at.x(), at.y(), at.z()}};
            ds.Replace(ipp.GetAsDataElement());
            gdcm::Attribute<0x0018, 0x1120> tilt = {tiltDeg};
            ds.Replace(tilt.GetAsDataElement());
            gdcm::Attribute<0x0018, 0x0050> thickness = {p.thicknessMm};
            ds.Replace(thickness.GetAsDataElement());
            gdcm::DataElement type(gdcm::Tag(0x0008, 0x0008));
            type.SetVR(gdcm::VR::CS);
            std::string text = p.imageType;
            if (text.size() % 2) text += ' ';
            type.SetByteValue(text.data(), std::uint32_t(text.size()));
            ds.Replace(type);
            gdcm::Attribute<0x0008, 0x0060> mod;
            mod.SetValue(modality.c_str());
            ds.Replace(mod.GetAsDataElement());
            gdcm::Writer w;
            w.SetFile(r.GetFile());
            w.SetFileName((dir / mSources[p.source].filename()).string().c_str());
            ASSERT_TRUE(w.Write());
        }
    }
    Vec3d position(double along) const { return mBase + Vec3d(0.0, kShearPerMm * along, along); }

    /// A source file's HU, decoded by GDCM: row j, column i at [j·columns + i].
    std::vector<double> sourceHu(std::size_t source) const
    {
        gdcm::ImageReader r;
        r.SetFileName(mSources[source].string().c_str());
        EXPECT_TRUE(r.Read());
        const gdcm::Image& img = r.GetImage();
        std::vector<std::uint16_t> raw(std::size_t(img.GetDimension(0)) * img.GetDimension(1));
        EXPECT_EQ(img.GetBufferLength(), raw.size() * 2);
        img.GetBuffer(reinterpret_cast<char*>(raw.data()));
        std::vector<double> hu;
        for (auto v : raw) hu.push_back(img.GetSlope() * v + img.GetIntercept());
        return hu;
    }

    std::vector<fs::path> mSources;
    Vec3d mBase{0, 0, 0};
};

TEST_F(CtImageTypes, ThinAddAndThickSlicesAtDistinctPositionsLoadAsOneStack)
{
    // Thin slices at 0, 3, ..., 57 mm; thick ones from 55.5 mm, 1.5 mm before the
    // last thin slice (the junction overlaps, by less than the 3 mm thickness), to 169.5.
    const std::vector<Planned> plan = thinThenThick(55.5);
    write(plan, mDir / "series");
    const DicomCatalog c = catalogDicom({mDir / "series"});
    ASSERT_EQ(c.series.size(), 1u);
    EXPECT_EQ(c.series.front().volumes, 1u) << c.series.front().volumeSummary;
    EXPECT_EQ(c.series.front().slices, 40u);

    // The steps vary (3, 1.5, 4.5, 6 mm) and the stack is sheared: refused in one
    // line that says so, loaded on a uniform grid with --resample.
    try {
        loadDicom({mDir / "series"});
        FAIL() << "a sheared stack of uneven steps loaded without resampling";
    } catch (const voxhap::IoError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("(0020,0032) ImagePositionPatient"), std::string::npos) << m;
        EXPECT_NE(m.find("--resample"), std::string::npos) << m;
        EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    }
    DicomOptions o;
    o.irregular = IrregularSlices::Resample;
    o.airHu = -5000.0f; // every voxel kept, to compare
    const Volume v = loadDicom({mDir / "series"}, o);
    ASSERT_TRUE(v.has(Channel::Hu));
    const double step = v.geometry().spacing.z();
    EXPECT_NEAR(step, 3.0, 1e-6) << "the lower median step of the joined stack";
    const Vec3d normal = v.geometry().direction.col(2);
    EXPECT_NEAR(normal.z(), 1.0, 1e-9);

    // Every plane of the grid against the source pixels: on a thin slice, its pixels;
    // between two slices (the thick part), the linear blend of the two along the
    // normal, each read at the voxel's own column and row (a whole pixel across,
    // kShearPerMm). The slices by position along the normal:
    std::map<double, std::size_t> byAlong;
    for (const Planned& p : plan) byAlong[p.along] = p.source;
    std::map<std::size_t, std::vector<double>> hu;
    auto acc = huGrid(v)->getConstAccessor();
    const auto box = v.indexBox();
    int compared = 0, blended = 0;
    for (int k = box.min.z(); k <= box.max.z(); ++k) {
        const Vec3d planeOrigin = v.indexToWorld(Vec3d(box.min.x(), box.min.y(), k));
        const double along = (planeOrigin - mBase).dot(normal);
        auto hi = byAlong.lower_bound(along - 1e-6);
        ASSERT_NE(hi, byAlong.end()) << "plane " << k << " past the last slice";
        auto lo = hi;
        const bool on = std::abs(hi->first - along) < 1e-6;
        if (!on) {
            ASSERT_NE(hi, byAlong.begin());
            --lo;
        }
        const double w = on ? 0.0 : (along - lo->first) / (hi->first - lo->first);
        for (const auto* s : {&*lo, &*hi}) {
            if (!hu.count(s->second)) hu[s->second] = sourceHu(s->second);
        }
        // Source pixel (i, j) of the slice at a: world base + shear + i·px·x + j·px·y.
        const auto sample = [&](const std::pair<const double, std::size_t>& s, const Vec3d& world) {
            const Vec3d d = world - position(s.first);
            const double i = d.x() / kPixelMm, j = d.y() / kPixelMm;
            EXPECT_NEAR(i, std::round(i), 1e-6);
            EXPECT_NEAR(j, std::round(j), 1e-6);
            const long ii = std::lround(i), jj = std::lround(j);
            if (ii < 0 || jj < 0 || ii >= 512 || jj >= 512) return std::nan("");
            return hu.at(s.second)[std::size_t(jj * 512 + ii)];
        };
        for (int j = box.min.y(); j <= box.max.y(); j += 37) {
            for (int i = box.min.x(); i <= box.max.x(); i += 41) {
                const Vec3d world = v.indexToWorld(Vec3d(i, j, k));
                const double a = sample(*lo, world), b = sample(*hi, world);
                if (std::isnan(a) || std::isnan(b)) continue; // outside a source slice: filled, not compared
                const double expected = (1.0 - w) * a + w * b;
                ASSERT_NEAR(acc.getValue(openvdb::Coord(i, j, k)), expected, kInterpolatedHu)
                    << "plane " << k << " (" << along << " mm) voxel " << i << "," << j;
                ++compared;
                blended += !on;
            }
        }
    }
    EXPECT_EQ(box.max.z() - box.min.z(), int(std::floor(169.5 / 3.0)))
        << "3 mm planes from the first slice to the last";
    EXPECT_GT(compared, 5000);
    EXPECT_GT(blended, 2000) << "the thick part is compared too";
}

// Two reconstructions of one range (thin and thick slices over the same 57 mm):
// two volumes, by image type, as before. A junction overlapping by more than a
// slice thickness (9.5 mm here) is not a continuation either. As MR the same
// series keeps its split by image type: MR image types tell contrasts apart.
TEST_F(CtImageTypes, SameRangeLongOverlapAndMrStaySeparateVolumes)
{
    const auto volumesOf = [&](const std::vector<Planned>& plan, const std::string& name, const std::string& modality) {
        write(plan, mDir / name, modality);
        const DicomCatalog c = catalogDicom({mDir / name});
        EXPECT_EQ(c.series.size(), 1u) << name;
        return c.series.empty() ? DicomSeriesInfo{} : c.series.front();
    };
    const DicomSeriesInfo same = volumesOf(thinThenThick(1.5, 10), "same-range", "CT"); // 1.5 .. 55.5
    EXPECT_EQ(same.volumes, 2u);
    EXPECT_EQ(same.separatedBy, "image type");
    const DicomSeriesInfo overlap = volumesOf(thinThenThick(47.5), "overlap", "CT"); // 47.5 < 57 − 3
    EXPECT_EQ(overlap.volumes, 2u);
    EXPECT_EQ(overlap.separatedBy, "image type");
    const DicomSeriesInfo mr = volumesOf(thinThenThick(55.5), "mr", "MR");
    EXPECT_EQ(mr.volumes, 2u);
    EXPECT_EQ(mr.separatedBy, "image type");
    // The control: the joinable series as CT is one volume (the test above).
    EXPECT_EQ(volumesOf(thinThenThick(55.5), "ct", "CT").volumes, 1u);
}

} // namespace
