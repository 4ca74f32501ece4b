// SPDX-License-Identifier: Apache-2.0
/// @file Cli.h
/// @brief What the voxhap subcommands share: argument parsing helpers, the
/// tissue table option and the exit-code convention.
///
/// Exit codes: 0 success, 1 the work failed (bad file, bad data), 2 bad
/// command-line arguments. Every failure prints exactly one line on stderr.
#pragma once

#include "core/Math.h"
#include "volume/TissueTable.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json_fwd.hpp>

#include <functional>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

namespace voxhap::haptic {
struct Scene;
} // namespace voxhap::haptic

namespace voxhap::render {
struct PlanFiles;
}

namespace voxhap::volume {
class Volume;
}

namespace voxhap::tools {

inline constexpr int kExitFailure = 1;
inline constexpr int kExitUsage = 2;

/// @brief A command-line value that parsed but makes no sense (exit 2).
class UsageError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// @brief Options every subcommand accepts.
struct CommonOptions {
    std::string tissues; ///< tissue table file; empty: the built-in table
    bool json = false;   ///< machine-readable output on stdout
};

/// @brief Add --tissues and --json to a subcommand.
void addCommonOptions(CLI::App& cmd, CommonOptions& opts);

/// @brief The tissue table the options name.
const volume::TissueTable& tissueTable(const CommonOptions& opts);

/// @brief haptic::loadScene(), then one line on stderr for each block the scene
/// left out, with the default taken (docs/scenes.md): defaults are never silent.
haptic::Scene loadSceneSayingDefaults(const std::string& nameOrPath);

/// @brief Parse "x,y,z" (three finite numbers). @throw UsageError naming @p option
Vec3d parseVec3(const std::string& text, const std::string& option);

/// @brief Parse "s" or "sx,sy,sz", each positive. @throw UsageError naming @p option
Vec3d parseSpacing(const std::string& text, const std::string& option);

/// @brief Rotation from Euler angles in degrees (about x, then y, then z).
Mat3d rotationFromDegrees(const Vec3d& degrees);

/// @brief The view options `render` and `view` share, against the loaded volume:
/// a CT window preset on a volume without HU, or a --point outside its bounds.
/// @throw UsageError naming the option
void checkViewOptions(const volume::Volume& v, const std::string& window, const std::optional<Vec3d>& point);

/// @brief Ctrl-C and SIGTERM as a request to stop: while a guard lives, they set a flag
/// that the command polls (interrupted()) instead of killing the process, so
/// that it can stop cleanly and write what it has; the previous handler comes
/// back when the guard goes, also when the command throws.
class InterruptGuard {
public:
    InterruptGuard();
    ~InterruptGuard();
    InterruptGuard(const InterruptGuard&) = delete;
    InterruptGuard& operator=(const InterruptGuard&) = delete;
    static bool interrupted();

private:
    void (*mPrevious)(int);
    void (*mPreviousTerm)(int);
};

/// @brief True when stderr is a terminal (progress output is shown only then).
bool stderrIsTerminal();

/// @brief A subcommand: registers its options and returns the action to run.
using Action = std::function<int()>;
Action registerPhantom(CLI::App& app);
Action registerInfo(CLI::App& app);
Action registerConvert(CLI::App& app);
Action registerSegment(CLI::App& app);
Action registerDemo(CLI::App& app);
Action registerBench(CLI::App& app);
Action registerSimulate(CLI::App& app);
Action registerServe(CLI::App& app);
Action registerRender(CLI::App& app);
Action registerPlot(CLI::App& app);
Action registerView(CLI::App& app);
Action registerPlan(CLI::App& app);
Action registerRegress(CLI::App& app);
Action registerBatch(CLI::App& app);
Action registerAssess(CLI::App& app);
Action registerFuse(CLI::App& app);

/// @brief The list of a plan's files, as `voxhap plan` and `voxhap demo` print it.
void printPlanFiles(std::ostream& os, const render::PlanFiles& f);

} // namespace voxhap::tools
