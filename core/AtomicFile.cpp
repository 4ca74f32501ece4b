// SPDX-License-Identifier: Apache-2.0
/// @file AtomicFile.cpp
#include "core/AtomicFile.h"

#include "core/Errors.h"

#include <array>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <stdexcept>
#include <sys/stat.h>
#include <unistd.h>

namespace voxhap {

namespace {

/// Temporaries in flight, as C strings a signal handler may unlink. A slot is
/// claimed with an atomic flag; more than kSlots writes at once go untracked
/// (still removed on failure, only not on a kill).
constexpr std::size_t kSlots = 64;
constexpr std::size_t kPathMax = 4096;
std::array<std::array<char, kPathMax>, kSlots> gPaths{};
std::array<std::atomic<int>, kSlots> gState{}; // 0 free, 1 being filled, 2 live

/// Registers a temporary for the life of the object.
class TrackedTemporary {
public:
    explicit TrackedTemporary(const std::filesystem::path& p)
    {
        const std::string s = p.string();
        if (s.size() + 1 > kPathMax) return;
        for (std::size_t i = 0; i < kSlots; ++i) {
            int expected = 0;
            if (gState[i].compare_exchange_strong(expected, 1)) {
                std::memcpy(gPaths[i].data(), s.c_str(), s.size() + 1);
                gState[i].store(2);
                mSlot = int(i);
                return;
            }
        }
    }
    ~TrackedTemporary()
    {
        if (mSlot >= 0) gState[std::size_t(mSlot)].store(0);
    }
    TrackedTemporary(const TrackedTemporary&) = delete;
    TrackedTemporary& operator=(const TrackedTemporary&) = delete;

private:
    int mSlot = -1;
};

/// fsync a file or folder; @p what names it in the error.
void flushToDisk(const std::filesystem::path& p, bool folder)
{
    const int fd = ::open(p.c_str(), folder ? (O_RDONLY | O_DIRECTORY) : O_RDONLY);
    if (fd < 0) throw std::runtime_error(std::string("cannot open for fsync: ") + std::strerror(errno));
    const int rc = ::fsync(fd);
    const int err = errno;
    ::close(fd);
    // Some file systems cannot fsync a folder (EINVAL); the rename is then as durable as they allow.
    if (rc != 0 && !(folder && (err == EINVAL || err == EROFS)))
        throw std::runtime_error(std::string("fsync failed: ") + std::strerror(err));
}

std::filesystem::path folderOf(const std::filesystem::path& file)
{
    return file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
}

void onFatalSignal(int sig)
{
    removeTemporaryFiles();
    std::signal(sig, SIG_DFL);
    std::raise(sig);
}

} // namespace

std::filesystem::path temporaryPathFor(const std::filesystem::path& file)
{
    return folderOf(file) / (".tmp." + std::to_string(::getpid()) + "." + file.filename().string());
}

void removeTemporaryFiles() noexcept
{
    for (std::size_t i = 0; i < kSlots; ++i) {
        if (gState[i].load() == 2) ::unlink(gPaths[i].data());
    }
}

void installTemporaryFileCleanup()
{
    std::signal(SIGTERM, onFatalSignal);
    std::signal(SIGHUP, onFatalSignal);
    struct sigaction current { };
    if (::sigaction(SIGINT, nullptr, &current) == 0 && current.sa_handler == SIG_DFL)
        std::signal(SIGINT, onFatalSignal);
}

void writeAtomically(const std::filesystem::path& file, const std::function<void(const std::filesystem::path&)>& write)
{
    const std::filesystem::path tmp = temporaryPathFor(file);
    const TrackedTemporary tracked(tmp);
    try {
        write(tmp);
        flushToDisk(tmp, false);
        std::filesystem::rename(tmp, file);
        flushToDisk(folderOf(file), true);
    } catch (const std::exception& e) {
        std::error_code ignored;
        std::filesystem::remove(tmp, ignored);
        throw IoError(file.string() + ": cannot write (" + e.what() + ")");
    }
}

void writeStreamAtomically(const std::filesystem::path& file, const std::function<void(std::ostream&)>& fill)
{
    writeAtomically(file, [&](const std::filesystem::path& tmp) {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) throw std::runtime_error("cannot create the file");
        fill(out);
        out.close();
        if (!out) throw std::runtime_error("write failed (disk full?)");
    });
}

void OutputSet::add(const std::filesystem::path& file, Writer write) { mOutputs.emplace_back(file, std::move(write)); }

void OutputSet::addStream(const std::filesystem::path& file, std::function<void(std::ostream&)> fill)
{
    add(file, [fill = std::move(fill)](const std::filesystem::path& tmp) {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) throw std::runtime_error("cannot create the file");
        fill(out);
        out.close();
        if (!out) throw std::runtime_error("write failed (disk full?)");
    });
}

struct StreamingOutput::State {
    std::filesystem::path temporary;
    TrackedTemporary tracked;
    std::ofstream out;
    explicit State(const std::filesystem::path& tmp)
        : temporary(tmp), tracked(tmp), out(tmp, std::ios::binary | std::ios::trunc)
    {
    }
};

StreamingOutput::StreamingOutput(std::filesystem::path file) : mFile(std::move(file))
{
    mState = std::make_unique<State>(temporaryPathFor(mFile));
    if (!mState->out) {
        std::error_code ignored;
        std::filesystem::remove(mState->temporary, ignored);
        throw IoError(mFile.string() + ": cannot write (cannot create the file)");
    }
}

StreamingOutput::~StreamingOutput()
{
    // Not handed over, or handed over and the commit failed: a temporary must not stay behind.
    std::error_code ignored;
    if (mState->out.is_open()) mState->out.close();
    std::filesystem::remove(mState->temporary, ignored);
}

std::ostream& StreamingOutput::stream() noexcept { return mState->out; }

void StreamingOutput::addTo(OutputSet& set)
{
    State* state = mState.get();
    // OutputSet writes each output to temporaryPathFor(file), the path this stream has
    // been growing under: the writer only closes it and checks that every write took.
    set.add(mFile, [state](const std::filesystem::path& tmp) {
        if (tmp != state->temporary) throw std::runtime_error("the streamed file is not at its temporary path");
        state->out.close();
        if (!state->out) throw std::runtime_error("write failed (disk full?)");
    });
}

void OutputSet::commit()
{
    const auto step = [&](const std::string& s) {
        if (afterStep) afterStep(s);
    };
    std::vector<std::unique_ptr<TrackedTemporary>> tracked;
    std::vector<std::filesystem::path> temporaries;
    const auto removeTemporaries = [&] {
        std::error_code ignored;
        for (const auto& t : temporaries) std::filesystem::remove(t, ignored);
    };
    // 1. Every new output written and on disk; the earlier ones untouched.
    for (const auto& [file, write] : mOutputs) {
        const std::filesystem::path tmp = temporaryPathFor(file);
        tracked.push_back(std::make_unique<TrackedTemporary>(tmp));
        temporaries.push_back(tmp);
        try {
            write(tmp);
            flushToDisk(tmp, false);
        } catch (const std::exception& e) {
            removeTemporaries();
            throw IoError(file.string() + ": cannot write (" + e.what() + ")");
        }
        step("written " + file.string());
    }
    // 2. The earlier outputs removed (folders flushed), so that no stale file
    //    can remain beside a new one; 3. the new ones renamed in.
    try {
        for (const auto& [file, write] : mOutputs) {
            std::filesystem::remove(file);
            flushToDisk(folderOf(file), true);
        }
        for (const auto& file : mStale) {
            if (std::filesystem::remove(file)) flushToDisk(folderOf(file), true);
        }
        step("removed the earlier outputs");
        for (std::size_t i = 0; i < mOutputs.size(); ++i) {
            std::filesystem::rename(temporaries[i], mOutputs[i].first);
            flushToDisk(folderOf(mOutputs[i].first), true);
            step("renamed " + mOutputs[i].first.string());
        }
    } catch (const std::exception& e) {
        removeTemporaries();
        throw IoError(std::string("cannot put the outputs in place (") + e.what() + ")");
    }
}

} // namespace voxhap
