// SPDX-License-Identifier: Apache-2.0
/// @file Cli.cpp
/// @brief Shared argument parsing for the voxhap subcommands.

#include "tools/Cli.h"

#include "haptic/scene/Scene.h"
#include "render/views/ViewTypes.h"
#include "volume/Volume.h"

#include <Eigen/Geometry>
#include <csignal>

#include <cmath>
#include <iostream>
#include <memory>
#include <sstream>
#include <unistd.h> // for isatty

namespace voxhap::tools {

void addCommonOptions(CLI::App& cmd, CommonOptions& opts)
{
    cmd.add_option("--tissues", opts.tissues, "Tissue table JSON (default: the built-in data/tissues.json)")
        ->check(CLI::ExistingFile);
    cmd.add_flag("--json", opts.json, "Print machine-readable JSON on stdout instead of text");
}

const volume::TissueTable& tissueTable(const CommonOptions& opts)
{
    if (opts.tissues.empty()) return volume::TissueTable::builtin();
    static std::unique_ptr<volume::TissueTable> loaded;
    loaded = std::make_unique<volume::TissueTable>(volume::TissueTable::load(opts.tissues));
    return *loaded;
}

haptic::Scene loadSceneSayingDefaults(const std::string& nameOrPath)
{
    haptic::Scene scene = haptic::loadScene(nameOrPath);
    for (const std::string& line : scene.defaulted)
        std::cerr << "voxhap: note: " << scene.origin << ": " << line << '\n';
    return scene;
}

Vec3d parseVec3(const std::string& text, const std::string& option)
{
    std::istringstream in(text);
    Vec3d v;
    char comma1 = 0, comma2 = 0;
    if (!(in >> v.x() >> comma1 >> v.y() >> comma2 >> v.z()) || comma1 != ',' || comma2 != ',' ||
        !(in >> std::ws).eof() || !v.allFinite()) {
        throw UsageError(option + ": expected three numbers x,y,z, got '" + text + "'");
    }
    return v;
}

Vec3d parseSpacing(const std::string& text, const std::string& option)
{
    Vec3d s;
    if (text.find(',') == std::string::npos) {
        std::istringstream in(text);
        double d = 0;
        if (!(in >> d) || !(in >> std::ws).eof())
            throw UsageError(option + ": expected a number or sx,sy,sz, got '" + text + "'");
        s = Vec3d::Constant(d);
    } else {
        s = parseVec3(text, option);
    }
    for (int i = 0; i < 3; ++i) {
        if (!std::isfinite(s[i]) || s[i] < 0.01 || s[i] > 100.0) {
            throw UsageError(option + ": spacing must be within 0.01..100 mm, got '" + text + "'");
        }
    }
    return s;
}

Mat3d rotationFromDegrees(const Vec3d& degrees)
{
    using Eigen::AngleAxisd;
    return (AngleAxisd(degToRad(degrees.z()), Vec3d::UnitZ()) * AngleAxisd(degToRad(degrees.y()), Vec3d::UnitY()) *
        AngleAxisd(degToRad(degrees.x()), Vec3d::UnitX()))
        .toRotationMatrix();
}

void checkViewOptions(const volume::Volume& v, const std::string& window, const std::optional<Vec3d>& point)
{
    // The presets are Hounsfield windows: on MR they would show nothing true.
    if (!v.has(volume::Channel::Hu) && render::namesCtPreset(window)) {
        throw UsageError("--window " + window +
            ": a CT preset in HU; this is MR: give WIDTH,LEVEL in its units "
            "(ms for T1, a.u. otherwise), or leave it out for the body's 1st-99th percentile");
    }
    if (point) {
        const auto b = v.worldBounds();
        if ((point->array() < b[0].array()).any() || (point->array() > b[1].array()).any()) {
            throw UsageError("--point lies outside the volume's bounds");
        }
    }
}

namespace {
volatile std::sig_atomic_t gInterrupted = 0;
extern "C" void onInterrupt(int) { gInterrupted = 1; }
} // namespace

InterruptGuard::InterruptGuard()
{
    gInterrupted = 0;
    mPrevious = std::signal(SIGINT, onInterrupt);
    // SIGTERM (a service manager, kill) stops the same way: force released, outputs written.
    mPreviousTerm = std::signal(SIGTERM, onInterrupt);
}

InterruptGuard::~InterruptGuard()
{
    std::signal(SIGINT, mPrevious);
    std::signal(SIGTERM, mPreviousTerm);
}

bool InterruptGuard::interrupted() { return gInterrupted != 0; }

bool stderrIsTerminal() { return ::isatty(STDERR_FILENO) == 1; }

} // namespace voxhap::tools
