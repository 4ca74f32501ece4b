// SPDX-License-Identifier: Apache-2.0
/// @file TestAtomicFile.cpp
/// @brief Outputs appear whole or not at all: a failing writer leaves the
/// earlier file and no temporary; a set of outputs killed at any step of its
/// commit never leaves a new file beside a stale one; a SIGTERM removes the
/// temporaries before the process dies.

#include "common/TempDirTest.h"

#include "core/AtomicFile.h"
#include "core/Errors.h"

#include <gtest/gtest.h>

#include <csignal>
#include <fstream>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace voxhap {
namespace {

namespace fs = std::filesystem;

class AtomicFile : public test::TempDirTest {
protected:
    static std::string read(const fs::path& p)
    {
        std::ifstream in(p, std::ios::binary);
        std::ostringstream s;
        s << in.rdbuf();
        return s.str();
    }
    static void put(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }
    /// Files of the folder whose name holds ".tmp.": temporaries left behind.
    int temporaries() const
    {
        int n = 0;
        for (const auto& e : fs::directory_iterator(mDir))
            n += e.path().filename().string().find(".tmp.") != std::string::npos;
        return n;
    }
    /// Run @p body in a child process; @return its wait status.
    template <typename Body> static int inChild(Body&& body)
    {
        const pid_t pid = ::fork();
        if (pid == 0) {
            body();
            ::_exit(0);
        }
        int status = 0;
        ::waitpid(pid, &status, 0);
        return status;
    }
};

TEST_F(AtomicFile, TemporaryLivesBesideTheTargetAndKeepsItsExtensions)
{
    const fs::path tmp = temporaryPathFor(mDir / "labels.nii.gz");
    EXPECT_EQ(tmp.parent_path(), mDir); // same folder: the rename cannot cross file systems
    EXPECT_EQ(tmp.filename().string(), ".tmp." + std::to_string(::getpid()) + ".labels.nii.gz");
}

TEST_F(AtomicFile, FailingWriterKeepsTheEarlierFileAndLeavesNoTemporary)
{
    put(mDir / "out.json", "old");
    EXPECT_THROW(writeStreamAtomically(mDir / "out.json",
                     [](std::ostream& o) {
                         o << "half of the new";
                         throw std::runtime_error("the writer failed");
                     }),
        IoError);
    EXPECT_EQ(read(mDir / "out.json"), "old");
    EXPECT_EQ(temporaries(), 0);
    writeStreamAtomically(mDir / "out.json", [](std::ostream& o) { o << "new"; });
    EXPECT_EQ(read(mDir / "out.json"), "new");
    EXPECT_EQ(temporaries(), 0);
}

// Kill the commit after each of its steps in turn (a child process dies of
// SIGTERM there, through the cleanup handler): whatever the step, every output
// present is either all old or all new, and no temporary is left.
TEST_F(AtomicFile, OutputSetKilledAtAnyStepNeverMixesNewAndStale)
{
    const std::vector<std::string> names{"seg.vdb", "labels.nrrd", "metrics.json"};
    int steps = 0;
    for (int killAt = 0;; ++killAt) {
        for (const auto& n : names) put(mDir / n, "old " + n);
        int reached = 0;
        const int status = inChild([&] {
            installTemporaryFileCleanup();
            OutputSet set;
            for (const auto& n : names) set.addStream(mDir / n, [n](std::ostream& o) { o << "new " << n; });
            set.afterStep = [&](const std::string&) {
                if (reached++ == killAt) std::raise(SIGTERM);
            };
            set.commit();
        });
        const bool killed = WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM;
        int olds = 0, news = 0;
        for (const auto& n : names) {
            if (!fs::exists(mDir / n)) continue;
            const std::string text = read(mDir / n);
            olds += text == "old " + n;
            news += text == "new " + n;
        }
        EXPECT_TRUE(olds == 0 || news == 0)
            << "killed after step " << killAt << ": " << olds << " old beside " << news << " new";
        EXPECT_EQ(temporaries(), 0) << "killed after step " << killAt;
        if (!killed) { // the commit ran to its end: every output new
            EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
            EXPECT_EQ(news, 3);
            break;
        }
        ++steps;
        ASSERT_LT(killAt, 20) << "the commit never finished";
    }
    // Three writes, one removal step, three renames: seven places to be killed.
    EXPECT_EQ(steps, 7);
}

TEST_F(AtomicFile, OutputSetWhoseWriterFailsKeepsEveryEarlierOutput)
{
    put(mDir / "a.csv", "old a");
    put(mDir / "b.csv", "old b");
    OutputSet set;
    set.addStream(mDir / "a.csv", [](std::ostream& o) { o << "new a"; });
    set.addStream(mDir / "b.csv", [](std::ostream&) { throw std::runtime_error("no space"); });
    try {
        set.commit();
        FAIL() << "no error";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("b.csv"), std::string::npos) << e.what();
    }
    EXPECT_EQ(read(mDir / "a.csv"), "old a");
    EXPECT_EQ(read(mDir / "b.csv"), "old b");
    EXPECT_EQ(temporaries(), 0);
}

// A SIGTERM while a write is under way: the process dies of SIGTERM (the
// handler re-raises it) and its temporary is gone.
// A file the set is told to remove goes with the replaced ones (after every new
// output is written, before any is renamed in), and only on commit.
TEST_F(AtomicFile, OutputSetRemovesAStaleOutputItDoesNotReplace)
{
    const fs::path table = mDir / "table.csv", plot = mDir / "plot.png";
    std::ofstream(table) << "old\n";
    std::ofstream(plot) << "old picture\n";
    OutputSet set;
    set.addStream(table, [](std::ostream& o) { o << "new\n"; });
    set.remove(plot);
    std::vector<std::string> steps;
    set.afterStep = [&](const std::string& step) {
        steps.push_back(step);
        if (step.rfind("written", 0) == 0)
            EXPECT_TRUE(fs::exists(plot)) << "removed before the new outputs were written";
    };
    set.commit();
    EXPECT_FALSE(fs::exists(plot));
    std::string line;
    std::getline(std::ifstream(table), line);
    EXPECT_EQ(line, "new");
    OutputSet nothingThere;
    nothingThere.remove(mDir / "never-written.png"); // an absent stale file is no error
    EXPECT_NO_THROW(nothingThere.commit());
}

TEST_F(AtomicFile, SigtermDuringAWriteRemovesTheTemporary)
{
    const fs::path target = mDir / "big.vdb";
    const int status = inChild([&] {
        installTemporaryFileCleanup();
        writeAtomically(target, [](const fs::path& tmp) {
            std::ofstream(tmp) << "part of a large file";
            std::raise(SIGTERM);
        });
    });
    ASSERT_TRUE(WIFSIGNALED(status));
    EXPECT_EQ(WTERMSIG(status), SIGTERM);
    EXPECT_FALSE(fs::exists(target));
    EXPECT_EQ(temporaries(), 0);
}

} // namespace
} // namespace voxhap
