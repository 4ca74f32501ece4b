// SPDX-License-Identifier: Apache-2.0
/// @file CmdRegress.cpp
/// @brief `voxhap regress [SUITE]`: regression tests of force profiles on phantom
/// volumes against baselines and closed forms (regress/Regress.h).
///
/// Exit codes are regress's own (docs/reference.md "Regression testing a simulator"):
/// 0 every case passed (or --update wrote the baselines), 1 a regression,
/// 2 a bad suite, baseline or other input, in one line naming the file, the
/// case and the field.

#include "tools/Cli.h"

#include "core/AtomicFile.h"
#include "core/Errors.h"
#include "regress/Regress.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <iostream>
#include <memory>

#include <unistd.h>

namespace voxhap::tools {

namespace {

struct RegressCliOptions {
    std::string suite, tissues, scenes, only, junit, plots = "voxhap-regress";
    int threads = 0;
    bool update = false, json = false, noPlots = false;
};

int run(const RegressCliOptions& o)
{
    regress::RegressResult result;
    // The JUnit file's folder is checked before the suite runs: a report that
    // cannot be written is bad input (exit 2), not a regression found late.
    if (!o.junit.empty()) {
        const std::filesystem::path dir = std::filesystem::path(o.junit).parent_path();
        if (::access((dir.empty() ? std::filesystem::path(".") : dir).c_str(), W_OK) != 0) {
            std::cerr << "voxhap regress: error: --junit " << o.junit << ": the folder "
                      << (dir.empty() ? std::string(".") : dir.string()) << " does not exist or is not writable\n";
            return kExitUsage;
        }
    }
    try {
        const regress::Suite suite = o.suite.empty() ? regress::builtinSuite() : regress::loadSuite(o.suite);
        regress::RegressOptions ro;
        ro.run.tissues = o.tissues;
        ro.run.scenesDir = o.scenes;
        ro.run.threads = o.threads;
        ro.only = o.only;
        ro.update = o.update;
        if (!o.noPlots) ro.plotDir = o.plots;
        result = regress::runRegression(suite, ro);
    } catch (const Error& e) {
        // A bad suite, baseline, scene or tissue table: exit 2, not 1 (1 is a regression).
        std::cerr << "voxhap regress: error: " << e.what() << '\n';
        return kExitUsage;
    }
    if (!o.junit.empty()) {
        const std::string xml = regress::junitXml(result);
        try {
            writeStreamAtomically(o.junit, [&](std::ostream& out) { out << xml; });
        } catch (const Error& e) {
            std::cerr << "voxhap regress: error: --junit " << e.what() << '\n';
            return kExitUsage;
        }
    }
    if (o.json)
        std::cout << regress::reportJson(result).dump(2) << '\n';
    else
        regress::printReport(std::cout, result);
    return o.update || result.failed() == 0 ? 0 : kExitFailure;
}

} // namespace

Action registerRegress(CLI::App& app)
{
    auto o = std::make_shared<RegressCliOptions>();
    CLI::App* cmd = app.add_subcommand("regress",
        "Regression-test force profiles on phantoms against baselines and closed forms "
        "(exit 0 pass, 1 regression, 2 bad input)");
    cmd->add_option(
        "suite", o->suite, "Suite file (JSON, schema in data/regress/README.md; default: the built-in suite)");
    cmd->add_option("--tissues", o->tissues, "Run every case with this tissue table instead of its own");
    cmd->add_option("--scenes", o->scenes, "Scene NAME resolves to DIR/NAME.json where that file exists")
        ->check(CLI::ExistingDirectory);
    cmd->add_option("--only", o->only, "Only the cases matching: a glob or a substring; several separated by commas");
    cmd->add_flag("--update", o->update, "Write each selected case's baseline (atomically) and list what changed");
    cmd->add_option("--junit", o->junit, "Also write a JUnit XML report to this file");
    cmd->add_option("--plots", o->plots, "Folder of the failing cases' PNGs (default voxhap-regress)");
    cmd->add_flag("--no-plots", o->noPlots, "Draw no PNG");
    cmd->add_option("--threads", o->threads, "Threads (default: all cores); results do not depend on it")
        ->check(CLI::Range(1, 1024));
    cmd->add_flag("--json", o->json, "Machine-readable report on stdout");
    return [o] { return run(*o); };
}

} // namespace voxhap::tools
