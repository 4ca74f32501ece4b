// SPDX-License-Identifier: Apache-2.0
/// @file main.cpp
/// @brief The `voxhap` command: subcommand dispatch and the one-line error convention.

#include "core/AtomicFile.h"
#include "core/Version.h"
#include "tools/Cli.h"

#include <iostream>
#include <map>

int main(int argc, char** argv)
{
    using namespace voxhap::tools;
    // A kill (SIGTERM, SIGHUP, Ctrl-C where a command does not handle it) removes the
    // temporaries of unfinished outputs: no *.tmp.* file stays behind.
    voxhap::installTemporaryFileCleanup();
    CLI::App app{"voxhap: needle-insertion force rendering from patient volumes.\n"
                 "World space is patient LPS in millimetres. Run `voxhap <command> --help` for details."};
    app.require_subcommand(1);
    app.set_version_flag("--version", "voxhap " + std::string(voxhap::kVersion));
    std::map<std::string, Action> actions{
        {"demo", registerDemo(app)},
        {"phantom", registerPhantom(app)},
        {"info", registerInfo(app)},
        {"convert", registerConvert(app)},
        {"fuse", registerFuse(app)},
        {"segment", registerSegment(app)},
        {"plan", registerPlan(app)},
        {"simulate", registerSimulate(app)},
        {"serve", registerServe(app)},
        {"render", registerRender(app)},
        {"plot", registerPlot(app)},
        {"view", registerView(app)},
        {"bench", registerBench(app)},
        {"regress", registerRegress(app)},
        {"batch", registerBatch(app)},
        {"assess", registerAssess(app)},
    };

    if (argc > 1 && argv[1][0] != '-' && !actions.count(argv[1])) {
        std::string known;
        for (const auto& [name, action] : actions) known += (known.empty() ? "" : ", ") + name;
        std::cerr << "voxhap: error: unknown command '" << argv[1] << "' (expected one of: " << known << ")\n";
        return kExitUsage;
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        std::cerr << "voxhap: error: " << e.what() << " (see --help)\n";
        return kExitUsage;
    }

    const std::string name = app.get_subcommands().front()->get_name();
    try {
        return actions.at(name)();
    } catch (const UsageError& e) {
        std::cerr << "voxhap " << name << ": error: " << e.what() << " (see --help)\n";
        return kExitUsage;
    } catch (const std::exception& e) {
        std::cerr << "voxhap " << name << ": error: " << e.what() << '\n';
        return kExitFailure;
    }
}
