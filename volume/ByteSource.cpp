// SPDX-License-Identifier: Apache-2.0
/// @file ByteSource.cpp
/// @brief Raw or zlib-inflated file bytes.

#include "volume/ByteSource.h"

#include "volume/Errors.h"

#include <zlib.h>

#include <algorithm>
#include <fstream>
#include <string>
#include <vector>

namespace voxhap::volume {

struct ByteSource::Impl {
    std::string name;
    std::ifstream in;
    bool compressed = false;
    z_stream z{};
    bool zOpen = false, zEnd = false;
    std::vector<char> buf;
};

ByteSource::ByteSource(const std::filesystem::path& file, std::uint64_t offset, bool compressed, std::uint64_t skip)
    : mImpl(std::make_unique<Impl>())
{
    mImpl->name = file.string();
    mImpl->in.open(file, std::ios::binary);
    if (!mImpl->in) throw IoError(mImpl->name + ": cannot open");
    mImpl->in.seekg(std::streamoff(offset));
    mImpl->compressed = compressed;
    if (compressed) {
        // windowBits 15 + 32: accept a gzip or a zlib header (NRRD and NIfTI
        // use gzip, MetaImage zlib).
        if (inflateInit2(&mImpl->z, 15 + 32) != Z_OK) throw IoError(mImpl->name + ": zlib initialisation failed");
        mImpl->zOpen = true;
        mImpl->buf.resize(1 << 16);
    }
    std::vector<char> discard(1 << 12);
    while (skip > 0) {
        const std::size_t n = std::size_t(std::min<std::uint64_t>(skip, discard.size()));
        if (read(discard.data(), n) != n) throw IoError(mImpl->name + ": data: the file ends before its data starts (truncated file)");
        skip -= n;
    }
}

ByteSource::~ByteSource()
{
    if (mImpl->zOpen) inflateEnd(&mImpl->z);
}

std::size_t ByteSource::read(void* out, std::size_t n)
{
    Impl& m = *mImpl;
    if (!m.compressed) {
        m.in.read(static_cast<char*>(out), std::streamsize(n));
        return std::size_t(m.in.gcount());
    }
    m.z.next_out = static_cast<Bytef*>(out);
    m.z.avail_out = uInt(n);
    while (m.z.avail_out > 0 && !m.zEnd) {
        if (m.z.avail_in == 0) {
            m.in.read(m.buf.data(), std::streamsize(m.buf.size()));
            const auto got = m.in.gcount();
            if (got <= 0) break; // compressed stream ends early: the caller sees a short read
            m.z.next_in = reinterpret_cast<Bytef*>(m.buf.data());
            m.z.avail_in = uInt(got);
        }
        const int rc = inflate(&m.z, Z_NO_FLUSH);
        if (rc == Z_STREAM_END) m.zEnd = true;
        else if (rc != Z_OK && rc != Z_BUF_ERROR) {
            throw IoError(m.name + ": data: corrupt compressed data (" + std::string(m.z.msg ? m.z.msg : "zlib error") + ")");
        }
    }
    return n - m.z.avail_out;
}

} // namespace voxhap::volume
