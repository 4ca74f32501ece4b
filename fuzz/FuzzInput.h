// SPDX-License-Identifier: Apache-2.0
/// @file FuzzInput.h
/// @brief What every fuzz target checks beyond "no crash": a refused input is
/// refused with voxhap's one-line message that names the file first.
#pragma once

#include "core/Errors.h"

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <unistd.h>

namespace voxhap::fuzz {

/// @brief A finding beyond a crash: an accepted input whose value breaks what
/// the parser promises. Prints @p what and aborts, so that libFuzzer stops.
[[noreturn]] inline void finding(const std::string& what)
{
    std::fprintf(stderr, "content check failed: %s\n", what.c_str());
    std::abort();
}

/// @brief Abort (a finding) unless @p e reads "<file>: ..." on one line, or
/// "<also>: ..." when @p also is given (a series names its folder).
inline void checkRefusal(const Error& e, const std::string& file, const std::string& also = {})
{
    const std::string_view m = e.what();
    const bool named = m.rfind(file + ": ", 0) == 0 || (!also.empty() && m.rfind(also + ": ", 0) == 0);
    if (!named || m.find('\n') != std::string_view::npos) {
        std::fprintf(stderr, "refusal message breaks the convention: %s\n", e.what());
        std::abort();
    }
}

/// @brief Run @p parse on the input as text named @p file; a refusal must
/// follow the message convention, anything else thrown is a finding.
template <typename Parse>
int parseText(const std::uint8_t* data, std::size_t size, const std::string& file, Parse parse)
{
    try {
        parse(std::string_view(reinterpret_cast<const char*>(data), size), file);
    } catch (const Error& e) {
        checkRefusal(e, file);
    }
    return 0;
}

/// @brief A scratch file for parsers that read from a path, one per process,
/// named with @p suffix (readers look at extensions), removed at exit.
class ScratchFile {
public:
    explicit ScratchFile(const std::string& suffix)
    {
        const auto dir = std::filesystem::temp_directory_path();
        mPath = dir / ("voxhap-fuzz-" + std::to_string(::getpid()) + suffix);
    }
    ~ScratchFile()
    {
        std::error_code ec;
        std::filesystem::remove(mPath, ec);
    }
    const std::filesystem::path& write(const std::uint8_t* data, std::size_t size)
    {
        std::ofstream out(mPath, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
        return mPath;
    }

private:
    std::filesystem::path mPath;
};

} // namespace voxhap::fuzz
