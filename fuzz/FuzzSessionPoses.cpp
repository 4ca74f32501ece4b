// SPDX-License-Identifier: Apache-2.0
/// @file FuzzSessionPoses.cpp
/// @brief libFuzzer target: the session reader (readSessionPoses, what
/// `voxhap serve --device replay:FILE` plays). Besides "no crash" and the refusal
/// convention, accepted poses are checked: at least two, times strictly
/// increasing, every number finite, one pose per line after the header; and
/// written with the project's writer (writeSession) they read back to the same
/// poses: times exactly (written with 17 digits), positions and directions
/// within the writer's ten significant digits.

#include "FuzzInput.h"

#include "haptic/servo/Session.h"

#include <cmath>
#include <filesystem>
#include <string_view>
#include <unistd.h>

namespace {

using voxhap::fuzz::finding;
using voxhap::haptic::ServoRecord;

/// Lines after the header, as std::getline splits them, less the comment lines
/// (starting with '#', like session.csv's closing line) that the reader skips.
std::size_t linesAfterHeader(std::string_view text)
{
    std::size_t lines = 0, comments = 0;
    for (std::size_t at = 0; at < text.size(); ++lines) {
        const std::size_t end = text.find('\n', at);
        if (lines > 0 && text[at] == '#') ++comments;
        at = end == std::string_view::npos ? text.size() : end + 1;
    }
    return lines == 0 ? 0 : lines - 1 - comments;
}

void checkPoses(const std::vector<ServoRecord>& poses, std::string_view text)
{
    if (poses.size() < 2) finding("fewer than two records");
    if (poses.size() != linesAfterHeader(text)) finding("records and lines differ in number");
    for (std::size_t i = 0; i < poses.size(); ++i) {
        const ServoRecord& r = poses[i];
        if (!std::isfinite(r.timeS) || !r.tip.allFinite() || !r.direction.allFinite()) finding("a pose not finite");
        if (i > 0 && !(r.timeS > poses[i - 1].timeS)) finding("times do not increase");
    }
}

/// Equal to ten significant digits (writeSession's precision).
bool close(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(std::abs(a), std::abs(b)); }

/// A folder for the session written back, one per process, removed at exit.
struct ScratchFolder {
    std::filesystem::path path =
        std::filesystem::temp_directory_path() / ("voxhap-fuzz-" + std::to_string(::getpid()) + "-session");
    ~ScratchFolder()
    {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
};

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    static voxhap::fuzz::ScratchFile scratch(".csv");
    static ScratchFolder folder;
    const auto& file = scratch.write(data, size);
    std::vector<ServoRecord> poses;
    try {
        poses = voxhap::haptic::readSessionPoses(file);
    } catch (const voxhap::Error& e) {
        voxhap::fuzz::checkRefusal(e, file.string());
        return 0;
    }
    checkPoses(poses, std::string_view(reinterpret_cast<const char*>(data), size));

    // writeSession writes times with 17 significant digits: they read back exactly, still increasing.
    voxhap::haptic::Session session;
    session.records = poses;
    voxhap::haptic::writeSession(session, {}, folder.path);
    std::vector<ServoRecord> back;
    try {
        back = voxhap::haptic::readSessionPoses(folder.path / "session.csv");
    } catch (const voxhap::Error& e) {
        finding(std::string("the session written back is refused: ") + e.what());
    }
    if (back.size() != poses.size()) finding("the session written back has another number of records");
    for (std::size_t i = 0; i < poses.size(); ++i) {
        const ServoRecord &a = poses[i], &b = back[i];
        bool same = a.timeS == b.timeS;
        for (int c = 0; c < 3; ++c) same = same && close(a.tip[c], b.tip[c]) && close(a.direction[c], b.direction[c]);
        if (!same) finding("the session written back reads differently at record " + std::to_string(i));
    }
    return 0;
}
