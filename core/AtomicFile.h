// SPDX-License-Identifier: Apache-2.0
/// @file AtomicFile.h
/// @brief Outputs appear complete or not at all, and survive a power cut once
/// reported: each is written under a temporary name in the target's folder,
/// flushed to disk (fsync), renamed over the target, and the folder flushed.
/// On failure the temporary is removed and the error names the file; on
/// SIGTERM, SIGHUP or an unhandled SIGINT the temporaries of the process are
/// removed before it dies (installTemporaryFileCleanup).
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

namespace voxhap {

/// @brief The temporary a write of @p file uses: ".tmp.<pid>.<name>" in its
/// folder (same file system, so the rename is atomic; the name keeps its
/// extensions, so format detection by name still works).
std::filesystem::path temporaryPathFor(const std::filesystem::path& file);

/// @brief Call @p write with a temporary path beside @p file, fsync it, rename
/// it to @p file and fsync the folder.
/// @throw IoError "<file>: cannot write (<why>)" when @p write throws, or the
///        fsync or the rename fails
void writeAtomically(const std::filesystem::path& file, const std::function<void(const std::filesystem::path&)>& write);

/// @brief writeAtomically() for a stream: @p fill writes the content (binary mode).
/// @throw IoError as above, also when the stream fails (disk full)
void writeStreamAtomically(const std::filesystem::path& file, const std::function<void(std::ostream&)>& fill);

/// @brief Several outputs of one run that must not mix with an earlier run's:
/// commit() writes and flushes every temporary first; only then does it remove
/// the earlier outputs it will replace, and rename the new ones in. A failure
/// while writing leaves the earlier outputs untouched; a kill during the
/// renames leaves some new outputs and no old ones, never a new file beside a
/// stale one.
class OutputSet {
public:
    using Writer = std::function<void(const std::filesystem::path& temporary)>;
    void add(const std::filesystem::path& file, Writer write);
    void addStream(const std::filesystem::path& file, std::function<void(std::ostream&)> fill);
    /// @brief An output an earlier run may have left that this run does not
    /// produce (a plot that could not be drawn this time): removed together with
    /// the outputs being replaced, so that it cannot stand beside the new ones.
    void remove(const std::filesystem::path& file) { mStale.push_back(file); }
    /// @brief Write, flush and put in place every output added.
    /// @throw IoError naming the file that failed
    void commit();
    /// @brief Called after each step of commit() with a description (tests
    /// use it to stop a child process between two renames).
    std::function<void(const std::string& step)> afterStep;

private:
    std::vector<std::pair<std::filesystem::path, Writer>> mOutputs;
    std::vector<std::filesystem::path> mStale;
};

/// @brief A file written over a long run (a servo session for an hour at any
/// rate): it grows under its temporary name (temporaryPathFor), removed by a
/// kill like every temporary, and is put in place together with the run's
/// other outputs by an OutputSet (addTo). Until then the target is untouched;
/// destroyed without addTo(), the temporary is removed.
class StreamingOutput {
public:
    /// @throw IoError "<file>: cannot write (cannot create the file)"
    explicit StreamingOutput(std::filesystem::path file);
    ~StreamingOutput();
    StreamingOutput(const StreamingOutput&) = delete;
    StreamingOutput& operator=(const StreamingOutput&) = delete;
    std::ostream& stream() noexcept;
    const std::filesystem::path& file() const noexcept { return mFile; }
    /// @brief Hand the file to @p set: its commit() closes the stream (an error
    /// while writing, a full disk, fails the commit naming the file), flushes it
    /// and renames it in with the others. This object must outlive the commit.
    void addTo(OutputSet& set);

private:
    struct State;
    std::filesystem::path mFile;
    std::unique_ptr<State> mState;
};

/// @brief Remove every temporary this process has open; async-signal-safe
/// (unlink only). Called by the signal handlers below.
void removeTemporaryFiles() noexcept;

/// @brief Install handlers for SIGTERM and SIGHUP, and for SIGINT when it has
/// the default action, that remove the temporaries and then die of the same
/// signal. A command that handles SIGINT itself (serve, view) installs its own
/// handler over this one.
void installTemporaryFileCleanup();

} // namespace voxhap
