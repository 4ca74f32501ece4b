// SPDX-License-Identifier: Apache-2.0
/// @file CliRunner.h
/// @brief Runs the real `voxhap` binary in a scratch directory and checks the
/// command-line conventions: exit codes and exactly one line on stderr.
#pragma once

#include "common/TempDirTest.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <sys/wait.h>

namespace voxhap::test {

struct CliResult {
    int exitCode = -1;
    std::string out, err;
    std::size_t errLines() const { return std::size_t(std::count(err.begin(), err.end(), '\n')); }
};

inline std::string slurp(const std::filesystem::path& p)
{
    std::ifstream in(p);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

class CliTest : public TempDirTest {
protected:
    /// Run `voxhap <args>` in the test's directory; @p env prefixes the command
    /// (e.g. "env -u DISPLAY PATH=/nonexistent").
    CliResult run(const std::string& args, const std::string& env = "") const
    {
        const std::filesystem::path out = mDir / "stdout.txt", err = mDir / "stderr.txt";
        const std::string cmd = "cd '" + mDir.string() + "' && " + env + " '" VOXHAP_BINARY_DIR "/bin/voxhap' " + args +
            " >'" + out.string() + "' 2>'" + err.string() + "'";
        const int status = std::system(cmd.c_str());
        CliResult r;
        r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        r.out = slurp(out);
        r.err = slurp(err);
        std::filesystem::remove(out);
        std::filesystem::remove(err);
        return r;
    }
};

/// Exit @p code with exactly one line on stderr that contains @p fragment.
inline void expectError(const CliResult& r, int code, const std::string& fragment)
{
    EXPECT_EQ(r.exitCode, code) << r.err;
    EXPECT_EQ(r.errLines(), 1u) << r.err;
    EXPECT_NE(r.err.find(fragment), std::string::npos) << r.err;
}
/// A usage error (exit 2).
inline void expectUsageError(const CliResult& r, const std::string& fragment) { expectError(r, 2, fragment); }
/// A failure of the work, such as a bad file (exit 1).
inline void expectFailure(const CliResult& r, const std::string& fragment) { expectError(r, 1, fragment); }

} // namespace voxhap::test
