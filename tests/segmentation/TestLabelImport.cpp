// SPDX-License-Identifier: Apache-2.0
/// @file TestLabelImport.cpp
/// @brief Imported label maps: the mapping file's checks, resampling from another
/// geometry, and precedence over the automatic labels (issue 7 item 3).

#include "common/BuiltinTable.h"
#include "common/TempDirTest.h"
#include "core/Errors.h"
#include "phantoms/Phantoms.h"
#include "segmentation/LabelImport.h"
#include "segmentation/Segmentation.h"
#include "volume/Grids.h"
#include "volume/VolumeFile.h"

#include <gtest/gtest.h>

#include <fstream>

namespace voxhap::segmentation {
namespace {

using test::table;

TEST(LabelMapping, ParsesNamesAndIds)
{
    const LabelMapping m = parseLabelMapping(
        R"({"schema": "voxhap.label-mapping/1", "file": "seg.nrrd", "labels": {"1": "kidney", "7": 15}})", "map.json",
        table());
    EXPECT_EQ(m.tissueOf.at(1), table().at("kidney").id);
    EXPECT_EQ(m.tissueOf.at(7), 15);
    EXPECT_EQ(m.file, "seg.nrrd");
}

TEST(LabelMapping, RefusesBadFieldsWithOneLineNamingThem)
{
    const auto refuses = [](const std::string& json, const std::string& field) {
        try {
            parseLabelMapping(json, "map.json", table());
            ADD_FAILURE() << "accepted " << json;
        } catch (const ValueError& e) {
            const std::string what = e.what();
            EXPECT_EQ(what.rfind("map.json: ", 0), 0u) << what;
            EXPECT_NE(what.find(field), std::string::npos) << what;
            EXPECT_EQ(what.find('\n'), std::string::npos) << what;
        }
    };
    refuses(R"({"labels": {"1": "kidney"}})", "schema");
    refuses(R"({"schema": "voxhap.label-mapping/1", "labels": {"1": "spleen"}})", "labels.1");
    refuses(R"({"schema": "voxhap.label-mapping/1", "labels": {"one": "kidney"}})", "labels.one");
    refuses(R"({"schema": "voxhap.label-mapping/1", "labels": {"0": "kidney"}})", "labels.0");
    refuses(R"({"schema": "voxhap.label-mapping/1", "labels": {}})", "labels");
    refuses(R"({"schema": "voxhap.label-mapping/1", "labels": {"1": "kidney"}, "extra": 1})", "extra");
    refuses("not json", "not JSON");
}

class LabelImport : public test::TempDirTest { };

/// A label map on its own lattice (2 mm voxels, offset) holding value @p value in a box.
volume::Volume boxLabelMap(const Vec3d& lo, const Vec3d& hi, int value)
{
    volume::Geometry g;
    g.spacing = Vec3d(2.0, 2.0, 2.0);
    g.origin = Vec3d(-31.0, -61.0, -31.0);
    volume::Volume v(g, volume::IndexBox{Vec3i(0, 0, 0), Vec3i(31, 31, 31)});
    auto grid = volume::LabelGrid::create(0);
    auto acc = grid->getAccessor();
    for (int k = 0; k < 32; ++k) {
        for (int j = 0; j < 32; ++j) {
            for (int i = 0; i < 32; ++i) {
                const Vec3d w = v.indexToWorld(Vec3d(i, j, k));
                if ((w.array() >= lo.array()).all() && (w.array() <= hi.array()).all()) acc.setValue({i, j, k}, value);
            }
        }
    }
    v.setGrid(volume::Channel::Label, grid);
    return v;
}

TEST_F(LabelImport, ImportedLabelsTakePrecedenceInTheirExtentOnly)
{
    volume::SlabParams p;
    p.grid.spacing = Vec3d(1.0, 1.0, 1.0);
    volume::Volume v = volume::makePhantom(volume::slabModel(p, table()), p.grid, table());
    v.removeGrid(volume::Channel::Label);
    // Write the map as NRRD and read it back, as a user's Slicer export would arrive.
    const auto file = mDir / "imported.nrrd";
    volume::saveVolume(boxLabelMap(Vec3d(-5, -20, -5), Vec3d(5, -10, 5), 3), file);
    const volume::Volume map = volume::loadVolume(file);

    SegmentOptions o;
    o.imported = ImportedLabels{&map,
        parseLabelMapping(R"({"schema": "voxhap.label-mapping/1", "labels": {"3": "lesion"}})", "map.json", table()),
        file.string()};
    const SegmentReport r = segment(v, table(), o);
    EXPECT_GT(r.importedVoxels, 0);
    auto acc = volume::labelGrid(v)->getConstAccessor();
    const auto at = [&](const Vec3d& w) {
        const Vec3d ijk = v.worldToIndex(w);
        return acc.getValue(
            openvdb::Coord(int(std::lround(ijk.x())), int(std::lround(ijk.y())), int(std::lround(ijk.z()))));
    };
    const int lesion = table().at("lesion").id;
    EXPECT_EQ(at(Vec3d(0, -15, 0)), lesion);                  // inside the imported box: imported wins over muscle
    EXPECT_EQ(at(Vec3d(0, -25, 0)), table().at("muscle").id); // 10 mm fat then muscle (slab phantom), outside the box
    EXPECT_EQ(at(Vec3d(12, -15, 0)), table().at("muscle").id);
}

TEST_F(LabelImport, AValueMissingFromTheMappingIsRefused)
{
    volume::SlabParams p;
    volume::Volume v = volume::makePhantom(volume::slabModel(p, table()), p.grid, table());
    const volume::Volume map = boxLabelMap(Vec3d(-5, -20, -5), Vec3d(5, -10, 5), 9);
    SegmentOptions o;
    o.imported = ImportedLabels{&map,
        parseLabelMapping(R"({"schema": "voxhap.label-mapping/1", "labels": {"3": "lesion"}})", "map.json", table()),
        "imported.nrrd"};
    try {
        segment(v, table(), o);
        FAIL() << "accepted an unmapped value";
    } catch (const ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("imported.nrrd: value 9 is not in the label mapping"), std::string::npos)
            << e.what();
    }
}

} // namespace
} // namespace voxhap::segmentation
