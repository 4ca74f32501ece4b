// SPDX-License-Identifier: Apache-2.0
/// @file AtomicFile.cpp
#include "core/AtomicFile.h"

#include "core/Errors.h"

#include <fstream>
#include <stdexcept>
#include <unistd.h> // for getpid: a per-process temporary name

namespace voxhap {

void writeAtomically(const std::filesystem::path& file, const std::function<void(const std::filesystem::path&)>& write)
{
    std::filesystem::path tmp = file;
    tmp += ".tmp." + std::to_string(::getpid());
    try {
        write(tmp);
        std::filesystem::rename(tmp, file);
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

} // namespace voxhap
