// SPDX-License-Identifier: Apache-2.0
/// @file GzipFile.cpp
/// @brief Verified inflation of .dcm.gz files; private temporary folders.

#include "volume/io/GzipFile.h"

#include "core/Errors.h"
#include "volume/io/ByteSource.h"

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <vector>

namespace voxhap::volume {

TemporaryFolder::TemporaryFolder(const std::string& prefix)
{
    std::string pattern = (std::filesystem::temp_directory_path() / (prefix + "-XXXXXX")).string();
    if (!::mkdtemp(pattern.data())) throw IoError(pattern + ": cannot create a temporary folder");
    mPath = pattern;
}

TemporaryFolder::~TemporaryFolder()
{
    std::error_code ec;
    std::filesystem::remove_all(mPath, ec);
}

bool isGzipFile(const std::filesystem::path& file)
{
    std::ifstream in(file, std::ios::binary);
    unsigned char magic[2] = {};
    return in.read(reinterpret_cast<char*>(magic), 2) && magic[0] == 0x1f && magic[1] == 0x8b;
}

bool inflateDicomGzip(const std::filesystem::path& in, const std::filesystem::path& out, std::uint64_t capBytes)
{
    ByteSource src(in, 0, true);
    // The preamble and magic first: a compressed file that is not DICOM is
    // not inflated any further.
    char preamble[132];
    if (src.read(preamble, sizeof preamble) != sizeof preamble || std::memcmp(preamble + 128, "DICM", 4) != 0)
        return false;
    std::ofstream o(out, std::ios::binary | std::ios::trunc);
    if (!o) throw IoError(out.string() + ": cannot write an inflated copy of " + in.string());
    try {
        o.write(preamble, sizeof preamble);
        std::vector<char> buf(1 << 16);
        std::uint64_t total = sizeof preamble;
        for (std::size_t n; (n = src.read(buf.data(), buf.size())) > 0;) {
            total += n;
            if (total > capBytes) {
                throw IoError(in.string() + ": inflates to more than the memory cap of " +
                    std::to_string(capBytes >> 20) + " MiB");
            }
            o.write(buf.data(), std::streamsize(n));
        }
        src.finish();
        o.close();
        if (!o) throw IoError(out.string() + ": cannot write an inflated copy of " + in.string() + " (disk full?)");
    } catch (...) {
        o.close();
        std::error_code ec;
        std::filesystem::remove(out, ec);
        throw;
    }
    return true;
}

} // namespace voxhap::volume
