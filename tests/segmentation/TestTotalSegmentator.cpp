// SPDX-License-Identifier: Apache-2.0
/// @file TestTotalSegmentator.cpp
/// @brief TotalSegmentator v2 `total` output as imported labels (issue 23 item 8),
/// on files made from the torso phantom: the phantom's structures written as the
/// multilabel NIfTI and as a folder of per-class masks, with a vena cava and an
/// oesophagus drawn in (the phantom has neither). No real TotalSegmentator output
/// was tested: its models cannot be downloaded here.

#include "common/TempDirTest.h"
#include "core/Errors.h"
#include "phantoms/Phantoms.h"
#include "segmentation/Segmentation.h"
#include "segmentation/TotalSegmentator.h"
#include "volume/Grids.h"

#include <gtest/gtest.h>
#include <nifti2_io.h>

#include <functional>
#include <map>
#include <set>

namespace voxhap::segmentation {
namespace {

namespace fs = std::filesystem;
const volume::TissueTable& table() { return volume::TissueTable::builtin(); }

TEST(TotalSegmentator, MappingCoversThe117ClassesOfTheTotalTask)
{
    const auto& c = totalSegmentatorClasses();
    ASSERT_EQ(c.size(), 117u);
    std::set<std::string> names;
    for (std::size_t i = 0; i < c.size(); ++i) {
        EXPECT_EQ(c[i].id, int(i) + 1);
        EXPECT_TRUE(names.insert(c[i].name).second) << c[i].name;
    }
    // Spot checks against class_map["total"] of map_to_binary.py.
    EXPECT_STREQ(c[14].name, "esophagus");
    EXPECT_STREQ(c[51].name, "aorta");
    EXPECT_STREQ(c[62].name, "inferior_vena_cava");
    EXPECT_STREQ(c[78].name, "spinal_cord");
    EXPECT_STREQ(c[116].name, "costal_cartilages");
    const LabelMapping m = totalSegmentatorMapping(table());
    EXPECT_EQ(m.tissueOf.at(15), table().at("oesophagus").id);
    EXPECT_EQ(m.tissueOf.at(63), table().at("vein").id);
    EXPECT_EQ(m.tissueOf.at(62), table().at("vein").id);
    EXPECT_EQ(m.tissueOf.at(52), table().at("aorta").id);
    EXPECT_EQ(m.tissueOf.at(2), table().at("kidney").id);
    EXPECT_EQ(m.tissueOf.at(29), table().at("cancellous_bone").id);
    EXPECT_EQ(m.tissueOf.at(16), -1); // trachea: the CT's own labels
    EXPECT_EQ(m.tissueOf.at(kTissueMaskValue + table().at("lesion").id), table().at("lesion").id);
    EXPECT_TRUE(table().at("oesophagus").critical);
    EXPECT_TRUE(table().at("vein").critical);
}

class TotalSegmentatorFiles : public test::TempDirTest {
protected:
    static constexpr double kSpacing = 2.0;
    // A vena cava right of the aorta and an oesophagus in front of it, as tubes along z [mm].
    static constexpr double kTubeRadius = 7.0;

    void SetUp() override
    {
        TempDirTest::SetUp();
        nifti_set_debug_level(0);
        volume::PhantomSpec spec;
        spec.kind = "torso";
        volume::GridSpec g;
        g.spacing = Vec3d::Constant(kSpacing);
        mPhantom =
            std::make_unique<volume::Volume>(volume::makePhantom(volume::phantomModel(spec, table()), g, table()));
        mAorta = *volume::phantomLandmark(*mPhantom, "aorta");
    }

    Vec3d ivcCentre() const { return mAorta + Vec3d(-35.0, 0, 0); }        // LPS: −x is the patient's right
    Vec3d oesophagusCentre() const { return mAorta + Vec3d(0, -30.0, 0); } // −y is anterior

    /// The class a TotalSegmentator run would give voxel @p ijk of the phantom.
    int classAt(const Vec3i& ijk) const
    {
        const Vec3d w = mPhantom->indexToWorld(ijk.cast<double>());
        const std::int32_t l = volume::labelGrid(*mPhantom)->tree().getValue(openvdb::Coord(ijk.x(), ijk.y(), ijk.z()));
        const auto is = [&](const char* n) { return l == table().at(n).id; };
        if (is("aorta")) return 52;
        if (is("kidney")) return w.x() < 0 ? 2 : 3;
        if (is("lung")) return 12;
        if (is("spinal_cord")) return 79;
        if (is("cortical_bone") || is("cancellous_bone")) return 29;
        const auto inTube = [&](const Vec3d& c) { return (w - c).head<2>().norm() < kTubeRadius; };
        if (is("muscle") || is("fat") || is("soft_tissue")) {
            if (inTube(ivcCentre())) return 63;
            if (inTube(oesophagusCentre())) return 15;
        }
        return 0;
    }

    /// Write a NIfTI on the phantom's grid; values from @p f (LPS → RAS in the sform).
    fs::path writeNifti(const std::string& name, const std::function<float(const Vec3i&)>& f) const
    {
        const volume::IndexBox b = mPhantom->indexBox();
        const Vec3i d = b.dims();
        const int64_t dims[8] = {3, d.x(), d.y(), d.z(), 1, 1, 1, 1};
        nifti_image* nim = nifti_make_new_nim(dims, DT_FLOAT32, 1);
        float* data = static_cast<float*>(nim->data);
        for (int k = 0; k < d.z(); ++k)
            for (int j = 0; j < d.y(); ++j)
                for (int i = 0; i < d.x(); ++i)
                    data[(std::int64_t(k) * d.y() + j) * d.x() + i] = f(b.min + Vec3i(i, j, k));
        const Vec3d o = mPhantom->indexToWorld(b.min.cast<double>());
        nifti_dmat44 m{};
        m.m[0][0] = -kSpacing;
        m.m[1][1] = -kSpacing;
        m.m[2][2] = kSpacing;
        m.m[0][3] = -o.x();
        m.m[1][3] = -o.y();
        m.m[2][3] = o.z();
        m.m[3][3] = 1;
        nim->sform_code = NIFTI_XFORM_SCANNER_ANAT;
        nim->sto_xyz = m;
        nim->qform_code = 0;
        nim->pixdim[1] = nim->pixdim[2] = nim->pixdim[3] = kSpacing;
        nim->dx = nim->dy = nim->dz = kSpacing;
        const fs::path p = mDir / name;
        fs::create_directories(p.parent_path());
        nifti_set_filenames(nim, p.string().c_str(), 0, 1);
        nifti_image_write(nim);
        nifti_image_free(nim);
        return p;
    }

    /// The phantom segmented with the imported map at @p path (its own labels are the automatic ones).
    std::map<std::string, std::int64_t> segmentWith(const fs::path& path, volume::Volume& out) const
    {
        out = *mPhantom;
        const volume::Volume imported = loadTotalSegmentator(path, table());
        SegmentOptions so;
        so.automatic = false; // the phantom's own labels stand for the CT's automatic ones
        so.critical = {"aorta"};
        so.imported = ImportedLabels{&imported, totalSegmentatorMapping(table()), path.string()};
        segment(out, table(), so);
        std::map<std::string, std::int64_t> counts;
        for (auto it = volume::labelGrid(out)->cbeginValueOn(); it; ++it) ++counts[table().at(*it).name];
        return counts;
    }

    std::unique_ptr<volume::Volume> mPhantom;
    Vec3d mAorta;
};

TEST_F(TotalSegmentatorFiles, MultilabelFileLabelsTheNewOrgansAndKeepsTheCortex)
{
    const fs::path ml = writeNifti("total.nii.gz", [&](const Vec3i& ijk) { return float(classAt(ijk)); });
    std::int64_t ivc = 0, oes = 0;
    const volume::IndexBox b = mPhantom->indexBox();
    for (int k = b.min.z(); k <= b.max.z(); ++k)
        for (int j = b.min.y(); j <= b.max.y(); ++j)
            for (int i = b.min.x(); i <= b.max.x(); ++i) {
                const int c = classAt({i, j, k});
                ivc += c == 63;
                oes += c == 15;
            }
    ASSERT_GT(ivc, 100);
    ASSERT_GT(oes, 100);
    volume::Volume seg = *mPhantom;
    const auto counts = segmentWith(ml, seg);
    // Same grid, nearest neighbour: every class voxel becomes its tissue, no more, no fewer.
    EXPECT_EQ(counts.at("vein"), ivc);
    EXPECT_EQ(counts.at("oesophagus"), oes);
    auto acc = volume::labelGrid(seg)->getConstAccessor();
    auto truth = volume::labelGrid(*mPhantom)->getConstAccessor();
    const auto at = [&](const Vec3d& w) {
        const Vec3d q = seg.worldToIndex(w);
        return acc.getValue(openvdb::Coord(int(std::lround(q.x())), int(std::lround(q.y())), int(std::lround(q.z()))));
    };
    EXPECT_EQ(at(ivcCentre()), table().at("vein").id);
    EXPECT_EQ(at(oesophagusCentre()), table().at("oesophagus").id);
    EXPECT_EQ(at(mAorta), table().at("aorta").id);
    // The lesion is its own label: TotalSegmentator has no such class, so the import leaves it.
    EXPECT_EQ(at(*volume::phantomLandmark(*mPhantom, "lesion")), table().at("lesion").id);
    // The vertebra's class is bone: cortical voxels stay cortical, the rest is cancellous.
    std::int64_t cortical = 0, mismatched = 0;
    for (auto it = volume::labelGrid(*mPhantom)->cbeginValueOn(); it; ++it) {
        if (*it == table().at("cortical_bone").id) {
            ++cortical;
            mismatched += acc.getValue(it.getCoord()) != *it;
        }
    }
    EXPECT_GT(cortical, 0);
    EXPECT_EQ(mismatched, 0);
    (void)truth;
}

TEST_F(TotalSegmentatorFiles, FolderOfMasksGivesTheSameLabelsAndTakesALesionMask)
{
    const fs::path ml = writeNifti("total.nii.gz", [&](const Vec3i& ijk) { return float(classAt(ijk)); });
    for (int c : {2, 3, 12, 15, 29, 52, 63, 79}) {
        const std::string name = totalSegmentatorClasses()[std::size_t(c - 1)].name;
        writeNifti("masks/" + name + ".nii.gz", [&](const Vec3i& ijk) { return classAt(ijk) == c ? 1.0f : 0.0f; });
    }
    volume::Volume a = *mPhantom, b = *mPhantom;
    const auto ca = segmentWith(ml, a);
    const auto cb = segmentWith(mDir / "masks", b);
    EXPECT_EQ(ca, cb);
    // A lesion mask (voxhap's own tissue name) wins over the classes under it.
    const Vec3d lesion = *volume::phantomLandmark(*mPhantom, "lesion");
    writeNifti("masks/lesion.nii.gz", [&](const Vec3i& ijk) {
        return (mPhantom->indexToWorld(ijk.cast<double>()) - lesion).norm() < 12.0 ? 1.0f : 0.0f;
    });
    volume::Volume c = *mPhantom;
    const auto cc = segmentWith(mDir / "masks", c);
    EXPECT_GT(cc.at("lesion"), ca.at("lesion"));
    // Refusals name the file.
    writeNifti("masks/liver_tumour.nii.gz", [](const Vec3i&) { return 0.0f; });
    try {
        loadTotalSegmentator(mDir / "masks", table());
        FAIL() << "an unknown mask name was accepted";
    } catch (const ValueError& e) {
        EXPECT_NE(
            std::string(e.what()).find("liver_tumour.nii.gz: 'liver_tumour' is neither a class"), std::string::npos)
            << e.what();
    }
}

} // namespace
} // namespace voxhap::segmentation
