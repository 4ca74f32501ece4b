// SPDX-License-Identifier: Apache-2.0
/// @file TestPorcineRegistration.cpp
/// @brief The shared porcine pair (a GE CT scanned feet first, a GE 3 T
/// T2-weighted MR head first) registered by voxhap and, independently, by
/// Debian's elastix with the parameter file and start committed beside this
/// test. elastix's answer moves with its settings, so the test first holds
/// elastix to the final metric recorded with them, then measures the mean
/// distance between the two transforms over the CT body's voxels (HU > −500).

#include "common/Prerequisites.h"
#include "common/SharedData.h"
#include "common/TempDirTest.h"
#include "registration/Registration.h"
#include "volume/Grids.h"
#include "volume/VolumeFile.h"
#include "volume/io/NrrdFile.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>

namespace voxhap::registration {
namespace {

namespace fs = std::filesystem;

/// The agreement the fusion issue asks of voxhap and elastix over the body [mm].
constexpr double kAgreementMm = 1.5;
/// elastix's final Mattes MI may differ from the recorded run by this much and
/// still be the same optimum: its random sampler is seeded, but its threads sum
/// in another order from run to run [chosen: ten times the spread of five runs].
constexpr double kElastixMetricSlack = 0.005;
/// Every n-th CT voxel along i, j, k enters the comparison (the mean over
/// about 10⁵ body voxels; the transforms are affine, so the mean is smooth).
const Vec3i kStride(4, 4, 2);

fs::path elastixDir() { return fs::path(VOXHAP_SOURCE_DIR) / "tests" / "registration" / "elastix"; }
fs::path porcineDir() { return test::sharedDataDir() / "ct-mr-porcine"; }

bool onPath(const std::string& program)
{
    return std::system(("command -v " + program + " > /dev/null 2>&1").c_str()) == 0;
}

double recordedElastixMetric()
{
    std::ifstream in(elastixDir() / "porcine-expected.txt");
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("final_metric ", 0) == 0) return std::stod(line.substr(13));
    }
    ADD_FAILURE() << "porcine-expected.txt has no final_metric line";
    return 0.0;
}

/// The last "Final metric value" elastix logged (its finest resolution).
double elastixFinalMetric(const fs::path& log)
{
    std::ifstream in(log);
    std::string line;
    double value = 0.0;
    bool found = false;
    const std::regex re(R"(Final metric value\s*=\s*(-?[0-9.eE+-]+))");
    while (std::getline(in, line)) {
        std::smatch m;
        if (std::regex_search(line, m, re)) {
            value = std::stod(m[1]);
            found = true;
        }
    }
    EXPECT_TRUE(found) << "no final metric in " << log;
    return value;
}

class PorcineRegistration : public test::TempDirTest { };

TEST_F(PorcineRegistration, AgreesWithElastixOverTheBody)
{
    VOXHAP_REQUIRE_DIR(porcineDir() / "ct");
    VOXHAP_REQUIRE_DIR(porcineDir() / "mr-t2");
    VOXHAP_REQUIRE(onPath("elastix") && onPath("transformix"), "elastix and transformix (Debian package elastix)");
    const volume::Volume ct = volume::loadVolume(porcineDir() / "ct");
    const volume::Volume mr = volume::loadVolume(porcineDir() / "mr-t2");
    ASSERT_TRUE(mr.has(volume::Channel::Intensity)) << "a T2-weighted MR is an intensity grid";

    // elastix on uncompressed NRRD, as the bench times it.
    volume::saveNrrd(ct, volume::Channel::Hu, mDir / "ct.nrrd", volume::NrrdEncoding::Raw);
    volume::saveNrrd(mr, volume::Channel::Intensity, mDir / "mr.nrrd", volume::NrrdEncoding::Raw);
    const fs::path out = mDir / "elastix";
    fs::create_directories(out);
    const std::string cmd = "elastix -f " + (mDir / "ct.nrrd").string() + " -m " + (mDir / "mr.nrrd").string() +
        " -p " + (elastixDir() / "rigid-mattes.txt").string() + " -t0 " +
        (elastixDir() / "porcine-initial.txt").string() + " -out " + out.string() + " -threads 2 > " +
        (mDir / "elastix.out").string() + " 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    const double elastixMetric = elastixFinalMetric(out / "elastix.log");
    EXPECT_LE(elastixMetric, recordedElastixMetric() + kElastixMetricSlack)
        << "elastix did worse than the run recorded with its parameters";

    const RegistrationResult r = registerMrToCt(ct, mr);

    // The CT body's voxels, every kStride-th, through transformix.
    std::vector<Vec3d> points;
    const auto hu = volume::huGrid(ct);
    auto acc = hu->getConstAccessor();
    const auto& b = ct.indexBox();
    for (int k = b.min.z(); k <= b.max.z(); k += kStride.z())
        for (int j = b.min.y(); j <= b.max.y(); j += kStride.y())
            for (int i = b.min.x(); i <= b.max.x(); i += kStride.x())
                if (acc.getValue(openvdb::Coord(i, j, k)) > -500.0f) points.push_back(ct.indexToWorld(Vec3d(i, j, k)));
    ASSERT_GT(points.size(), 10000u);
    {
        std::ofstream pts(mDir / "points.txt");
        pts << "point\n" << points.size() << '\n';
        pts.precision(17);
        for (const Vec3d& p : points) pts << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    }
    const fs::path tout = mDir / "transformix";
    fs::create_directories(tout);
    const std::string tcmd = "transformix -def " + (mDir / "points.txt").string() + " -tp " +
        (out / "TransformParameters.0.txt").string() + " -out " + tout.string() + " > " +
        (mDir / "transformix.out").string() + " 2>&1";
    ASSERT_EQ(std::system(tcmd.c_str()), 0) << tcmd;
    std::ifstream in(tout / "outputpoints.txt");
    const std::regex re(R"(OutputPoint = \[\s*([-0-9.eE+]+)\s+([-0-9.eE+]+)\s+([-0-9.eE+]+)\s*\])");
    std::string line;
    std::size_t n = 0;
    double sum = 0.0, worst = 0.0;
    while (std::getline(in, line)) {
        std::smatch m;
        if (!std::regex_search(line, m, re)) continue;
        ASSERT_LT(n, points.size());
        const Vec3d e(std::stod(m[1]), std::stod(m[2]), std::stod(m[3]));
        const double d = (r.mrFromCt.apply(points[n]) - e).norm();
        sum += d;
        worst = std::max(worst, d);
        ++n;
    }
    ASSERT_EQ(n, points.size()) << "transformix mapped every point";
    const double mean = sum / double(n);
    RecordProperty("mean_distance_mm", std::to_string(mean));
    RecordProperty("max_distance_mm", std::to_string(worst));
    RecordProperty("elastix_final_metric", std::to_string(elastixMetric));
    RecordProperty("voxhap_final_metric", std::to_string(r.metricFinal));
    RecordProperty("voxhap_started_from", r.startedFrom);
    RecordProperty("voxhap_seconds", std::to_string(r.seconds));
    EXPECT_LE(mean, kAgreementMm) << "voxhap " << r.startedFrom << "; max " << worst << " mm";
    std::cout << "porcine: mean " << mean << " mm, max " << worst << " mm; elastix MI " << elastixMetric
              << ", voxhap MI " << r.metricFinal << " (" << r.startedFrom << ", " << r.seconds << " s)\n";
}

} // namespace
} // namespace voxhap::registration
