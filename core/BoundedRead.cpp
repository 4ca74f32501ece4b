// SPDX-License-Identifier: Apache-2.0
/// @file BoundedRead.cpp
/// @brief Regular files only, checked before and after opening (O_NONBLOCK, so
/// that a file swapped for a FIFO in between cannot block the open), read with
/// at most limit + 1 bytes requested.

#include "core/BoundedRead.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace voxhap {

namespace {

std::string boundedOneLine(std::string s)
{
    for (char& c : s) {
        if (c == '\n' || c == '\r') c = ' ';
    }
    return s;
}

std::string fileKind(mode_t mode)
{
    if (S_ISFIFO(mode)) return "a FIFO";
    if (S_ISCHR(mode)) return "a character device";
    if (S_ISBLK(mode)) return "a block device";
    if (S_ISSOCK(mode)) return "a socket";
    if (S_ISDIR(mode)) return "a directory";
    return "not a regular file";
}

std::string limitText(std::uint64_t bytes)
{
    if (bytes % (1u << 20) == 0) return std::to_string(bytes >> 20) + " MiB";
    return std::to_string(bytes) + " bytes";
}

struct ReadFd {
    int fd = -1;
    ~ReadFd()
    {
        if (fd >= 0) ::close(fd);
    }
};

} // namespace

void requireRegularFile(const std::filesystem::path& path, std::string_view what, bool allowDirectory)
{
    struct stat st { };
    if (::stat(path.c_str(), &st) != 0) return; // missing: the caller's own message
    if (S_ISREG(st.st_mode) || (allowDirectory && S_ISDIR(st.st_mode))) return;
    throw IoError(path.string() + ": file type: " + fileKind(st.st_mode) + ", not a regular file" +
        (allowDirectory ? " or a directory" : "") + "; the " + std::string(what) + " must be " +
        (allowDirectory ? "a file or a directory" : "a regular file"));
}

std::string readBoundedFile(const std::filesystem::path& file, std::string_view what, std::uint64_t limitBytes)
{
    const std::string name = file.string();
    const std::string input(what);
    const auto notRegular = [&](mode_t mode) {
        throw IoError(
            name + ": file type: " + fileKind(mode) + ", not a regular file; the " + input + " must be a regular file");
    };
    const auto tooLarge = [&](const std::string& size) {
        throw IoError(name + ": size: " + size + ", beyond the " + limitText(limitBytes) + " limit of a " + input);
    };
    // The type first, from the path: opening a FIFO for reading would wait for a writer.
    struct stat st { };
    if (::stat(name.c_str(), &st) != 0) {
        throw IoError(name + ": cannot open the " + input + " (" + std::strerror(errno) + ")");
    }
    if (!S_ISREG(st.st_mode)) notRegular(st.st_mode);
    if (std::uint64_t(st.st_size) > limitBytes) tooLarge(std::to_string(st.st_size) + " bytes");

    ReadFd f;
    f.fd = ::open(name.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
    if (f.fd < 0) throw IoError(name + ": cannot open the " + input + " (" + std::strerror(errno) + ")");
    if (::fstat(f.fd, &st) != 0 || !S_ISREG(st.st_mode)) notRegular(st.st_mode); // swapped since the check
    // Read at most limit + 1 bytes: a file that grows while read (or reports a
    // size of 0, as /proc does) is still bounded.
    std::string text;
    text.resize(std::size_t(std::min<std::uint64_t>(std::uint64_t(st.st_size), limitBytes)) + 1);
    std::size_t got = 0;
    for (;;) {
        if (got == text.size()) {
            if (got > limitBytes) tooLarge("more than " + std::to_string(limitBytes) + " bytes");
            text.resize(std::size_t(std::min<std::uint64_t>(limitBytes + 1, std::uint64_t(text.size()) * 2)));
        }
        const ssize_t n = ::read(f.fd, text.data() + got, text.size() - got);
        if (n < 0) {
            if (errno == EINTR) continue;
            throw IoError(name + ": cannot read the " + input + " (" + std::strerror(errno) + ")");
        }
        if (n == 0) break;
        got += std::size_t(n);
    }
    if (got > limitBytes) tooLarge("more than " + std::to_string(limitBytes) + " bytes");
    text.resize(got);
    return text;
}

nlohmann::json parseJsonText(std::string_view text, const std::string& origin)
{
    try {
        return nlohmann::json::parse(text.begin(), text.end());
    } catch (const nlohmann::json::exception& e) { // parse_error, out_of_range (1e99999), ...
        throw ValueError(origin + ": not valid JSON (" + boundedOneLine(e.what()) + ")");
    }
}

nlohmann::json readJsonFile(const std::filesystem::path& file, std::string_view what, std::uint64_t limitBytes)
{
    return parseJsonText(readBoundedFile(file, what, limitBytes), file.string());
}

} // namespace voxhap
