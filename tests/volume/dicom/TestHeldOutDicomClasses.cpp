// SPDX-License-Identifier: Apache-2.0
/// @file TestHeldOutDicomClasses.cpp
/// @brief The kinds of series the reference converter's validation sets cover,
/// built from the real series in ../shared/data by held_out_classes.py (pydicom
/// rewrites the headers, DCMTK and GDCM's tools re-encode the pixels): Siemens,
/// GE, Philips, Canon/Toshiba and an Agfa PACS export; enhanced CT and MR;
/// every transfer syntax Debian's tools write; time points, echoes and b-values
/// in each vendor's element. Each must load with the right material (CT in HU,
/// MR as its weighting says) and the voxels pydicom decodes from the
/// uncompressed source, or be refused in one line naming why.

#include "common/Prerequisites.h"
#include "common/SharedData.h"
#include "common/TempDirTest.h"

#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/dicom/DicomSeries.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace voxhap::volume;

/// Every class the builder makes: one that stops being built (a tool that
/// changed, a script edit) fails here instead of passing unseen.
const std::set<std::string> kClasses = {"siemens-mr", "ge-ct", "ge-mr", "philips-ct", "philips-mr", "canon-ct",
    "agfa-mr", "enhanced-mr", "enhanced-ct", "ts-implicit", "ts-big-endian", "ts-deflated", "ts-rle",
    "ts-jpeg-lossless-sv1", "ts-jpeg-lossless", "ts-jpeg-ls-lossless", "ts-jpeg-ls-near-lossless",
    "ts-jpeg-2000-lossless", "ts-ge-private", "4d-temporal", "4d-echoes", "4d-dwi-standard", "4d-dwi-siemens",
    "4d-dwi-ge", "4d-dwi-philips"};

bool onPath(const std::string& tool) { return std::system(("command -v " + tool + " >/dev/null 2>&1").c_str()) == 0; }

class HeldOutDicomClasses : public voxhap::test::TempDirTest { };

TEST_F(HeldOutDicomClasses, EveryClassLoadsWithItsMaterialOrIsRefusedInOneLine)
{
    VOXHAP_REQUIRE_DIR(voxhap::test::realCtDir());
    VOXHAP_REQUIRE_DIR(voxhap::test::flash2dDir());
    VOXHAP_REQUIRE_DIR(voxhap::test::sharedDataDir() / "ct-mr-porcine");
    for (const char* tool : {"dcmconv", "dcmcrle", "dcmcjpeg", "dcmcjpls"})
        VOXHAP_REQUIRE(onPath(tool), tool << " (Debian: dcmtk; tools/setup.sh installs it)");
    VOXHAP_REQUIRE(onPath("gdcmconv"), "gdcmconv (Debian: libgdcm-tools; tools/setup.sh installs it)");
    const std::string build = std::string(VOXHAP_PYTHON) + " " + VOXHAP_SOURCE_DIR +
        "/tests/volume/dicom/held_out_classes.py '" + voxhap::test::sharedDataDir().string() + "' '" +
        (mDir / "classes").string() + "' 2>" + (mDir / "build.log").string();
    ASSERT_EQ(std::system(build.c_str()), 0) << "held_out_classes.py failed: see " << mDir / "build.log";
    std::ifstream in(mDir / "classes" / "manifest.json");
    const nlohmann::json manifest = nlohmann::json::parse(in);

    std::set<std::string> seen;
    for (const nlohmann::json& c : manifest) {
        const std::string name = c.at("name");
        seen.insert(name);
        SCOPED_TRACE(name + ": " + c.at("stands_for").get<std::string>());
        const fs::path dir = mDir / "classes" / c.at("folder").get<std::string>();
        if (c.at("expect") == "refuse") {
            // The folder in one line; each file in one line naming why (what `info --verbose` lists).
            for (const fs::path& p : {dir, fs::directory_iterator(dir)->path()}) {
                try {
                    loadDicom({p});
                    ADD_FAILURE() << p << " loaded; expected a refusal";
                } catch (const voxhap::Error& e) {
                    const std::string m = e.what();
                    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
                    if (p != dir) {
                        EXPECT_NE(m.find(c.at("refusal").get<std::string>()), std::string::npos) << m;
                    }
                }
            }
            continue;
        }
        const DicomCatalog catalog = catalogDicom({dir});
        ASSERT_EQ(catalog.series.size(), 1u);
        const DicomSeriesInfo& s = catalog.series.front();
        EXPECT_EQ(s.modality, c.at("modality").get<std::string>());
        EXPECT_EQ(s.volumes, c.at("volumes").get<std::size_t>()) << s.volumeSummary << " " << s.problem;
        if (c.contains("separated_by")) {
            EXPECT_NE(s.separatedBy.find(c.at("separated_by").get<std::string>()), std::string::npos) << s.separatedBy;
        }
        if (c.at("weighting").is_string()) {
            EXPECT_EQ(s.weighting, c.at("weighting").get<std::string>());
        }

        // The stored values, rescaled: no air or background made inactive, no T1 normalisation.
        DicomOptions o;
        o.volume = c.at("load_volume").get<std::size_t>();
        o.airHu = -1e30f;
        o.airT1 = -1e30f;
        o.removeMrBackground = false;
        o.normaliseT1Weighted = false;
        std::optional<Volume> loaded;
        try {
            loaded.emplace(loadDicom({dir}, o));
        } catch (const voxhap::Error& e) {
            ADD_FAILURE() << "refused: " << e.what();
            continue;
        }
        const Volume& v = *loaded;
        const bool ct = c.at("modality") == "CT";
        ASSERT_TRUE(v.has(ct ? Channel::Hu : Channel::Intensity)) << "the material: HU for CT, intensity for MR";
        const std::vector<int> shape = c.at("shape"); // slices, rows, columns
        ASSERT_EQ(v.indexBox().dims(), voxhap::Vec3i(shape[2], shape[1], shape[0]));
        std::ifstream raw(mDir / "classes" / (name + ".raw"), std::ios::binary);
        std::vector<double> ref(static_cast<std::size_t>(shape[0]) * shape[1] * shape[2]);
        raw.read(reinterpret_cast<char*>(ref.data()), std::streamsize(ref.size() * sizeof(double)));
        ASSERT_TRUE(raw) << "reference voxels";
        const double tolerance = c.at("tolerance").get<double>();
        const auto grid = ct ? huGrid(v) : intensityGrid(v);
        auto acc = grid->getConstAccessor();
        const voxhap::Vec3i lo = v.indexBox().min;
        long compared = 0, worst = 0;
        double padding = std::nan("");
        if (c.at("padding").is_number()) padding = c.at("padding").get<double>(); // rescaled
        for (int k = 0; k < shape[0]; ++k) {
            for (int j = 0; j < shape[1]; ++j) {
                for (int i = 0; i < shape[2]; ++i) {
                    const double want = ref[(std::size_t(k) * shape[1] + j) * shape[2] + i];
                    if (want == padding) continue; // PixelPaddingValue: not tissue, made air
                    const double got = acc.getValue(openvdb::Coord(lo.x() + i, lo.y() + j, lo.z() + k));
                    if (std::abs(got - want) > tolerance) ++worst;
                    ++compared;
                }
            }
        }
        EXPECT_EQ(worst, 0) << "voxels beyond " << tolerance << " of pydicom's decode of the source";
        EXPECT_GT(compared, 10000);
    }
    EXPECT_EQ(seen, kClasses);
}

} // namespace
