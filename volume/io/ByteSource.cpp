// SPDX-License-Identifier: Apache-2.0
/// @file ByteSource.cpp
/// @brief Raw or zlib-inflated file bytes.

#include "volume/io/ByteSource.h"

#include "core/Errors.h"

#include <zlib.h>

#include <algorithm>
#include <fstream>
#include <string>
#include <vector>

namespace voxhap::volume {

struct ByteSource::Impl {
    std::string name;
    std::ifstream in;
    std::uint64_t offset = 0; ///< where the compressed data starts in the file
    std::uint64_t fed = 0;    ///< compressed bytes handed to zlib so far
    bool compressed = false;
    bool gzip = false; ///< gzip members (RFC 1952), not one zlib stream (RFC 1950): decides what may follow
    z_stream z{};
    bool zOpen = false, zEnd = false;
    std::vector<char> buf;

    /// Offset in the file of the next compressed byte zlib has not consumed.
    std::uint64_t position() const { return offset + fed - z.avail_in; }

    /// Top up zlib's input; false at the end of the file.
    bool refill()
    {
        if (z.avail_in > 0) return true;
        in.read(buf.data(), std::streamsize(buf.size()));
        const auto got = in.gcount();
        if (got <= 0) return false;
        z.next_in = reinterpret_cast<Bytef*>(buf.data());
        z.avail_in = uInt(got);
        fed += std::uint64_t(got);
        return true;
    }

    /// At the end of one member: start the next if a gzip member follows
    /// (concatenated members are one file, RFC 1952 §2.2); stop at the end of
    /// the file; refuse anything else. A zlib stream (RFC 1950) has no members:
    /// nothing may follow it.
    void nextMember()
    {
        if (!refill()) {
            zEnd = true;
            return;
        }
        const std::uint64_t at = position();
        if (!gzip) {
            throw IoError(name + ": data: bytes after the end of the zlib stream (at byte " + std::to_string(at) +
                "): the format allows none");
        }
        // A gzip member starts 1F 8B; read the second byte if it is not in the buffer yet.
        unsigned char first = z.next_in[0], second = 0;
        if (z.avail_in >= 2)
            second = z.next_in[1];
        else {
            in.clear();
            const auto back = in.tellg();
            in.seekg(std::streamoff(at + 1));
            char c = 0;
            if (in.get(c)) second = static_cast<unsigned char>(c);
            in.clear();
            in.seekg(back);
        }
        if (first != 0x1f || second != 0x8b) {
            throw IoError(name + ": data: bytes after the end of the compressed stream (at byte " + std::to_string(at) +
                ") are not another gzip member");
        }
        if (inflateReset(&z) != Z_OK) throw IoError(name + ": zlib reset failed");
    }

    /// One line for what inflate() refused. A failed trailer check is named by
    /// its field: zlib has just consumed the 4 bytes of that field (it reads
    /// them whole and checks them at once), so the field starts 4 bytes back.
    [[noreturn]] void refuse(int rc) const
    {
        const std::string msg = z.msg ? z.msg : "";
        const std::uint64_t at = position();
        if (msg == "incorrect data check") {
            throw IoError(name + ": data: " + (gzip ? "gzip trailer CRC-32" : "zlib trailer Adler-32") + " at byte " +
                std::to_string(at - 4) + " does not match the inflated data (corrupt stream or trailer)");
        }
        if (msg == "incorrect length check") {
            throw IoError(name + ": data: gzip trailer ISIZE (stored length) at byte " + std::to_string(at - 4) +
                " does not match the inflated length (corrupt stream or trailer)");
        }
        if (rc == Z_NEED_DICT) {
            throw IoError(name + ": data: the zlib stream at byte " + std::to_string(offset) +
                " needs a preset dictionary, which this format cannot supply");
        }
        throw IoError(name + ": data: corrupt compressed data near byte " + std::to_string(at) + " (" +
            (msg.empty() ? std::string("zlib error ") + std::to_string(rc) : msg) + ")");
    }
};

ByteSource::ByteSource(const std::filesystem::path& file, std::uint64_t offset, bool compressed, std::uint64_t skip)
    : mImpl(std::make_unique<Impl>())
{
    mImpl->name = file.string();
    mImpl->in.open(file, std::ios::binary);
    if (!mImpl->in) throw IoError(mImpl->name + ": cannot open");
    mImpl->in.seekg(std::streamoff(offset));
    mImpl->offset = offset;
    mImpl->compressed = compressed;
    if (compressed) {
        // windowBits 15 + 32: accept a gzip or a zlib header (NRRD and NIfTI
        // use gzip, MetaImage zlib).
        if (inflateInit2(&mImpl->z, 15 + 32) != Z_OK) throw IoError(mImpl->name + ": zlib initialisation failed");
        mImpl->zOpen = true;
        mImpl->buf.resize(1 << 16);
        // The wrapper decides what may follow the stream (nextMember): gzip
        // starts 1F 8B; anything else is left to inflate to accept as zlib or refuse.
        unsigned char magic[2] = {};
        mImpl->in.read(reinterpret_cast<char*>(magic), 2);
        mImpl->gzip = mImpl->in.gcount() == 2 && magic[0] == 0x1f && magic[1] == 0x8b;
        mImpl->in.clear();
        mImpl->in.seekg(std::streamoff(offset));
    }
    std::vector<char> discard(1 << 12);
    while (skip > 0) {
        const std::size_t n = std::size_t(std::min<std::uint64_t>(skip, discard.size()));
        if (read(discard.data(), n) != n)
            throw IoError(mImpl->name + ": data: the file ends before its data starts (truncated file)");
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
        // The file ends inside a member (its data or its trailer): a cut file,
        // refused here with the offset rather than left to look like a short volume.
        if (!m.refill()) {
            throw IoError(m.name + ": data: the compressed stream ends at byte " + std::to_string(m.position()) +
                " before its end and trailer (truncated file)");
        }
        const int rc = inflate(&m.z, Z_NO_FLUSH);
        if (rc == Z_STREAM_END)
            m.nextMember();
        else if (rc != Z_OK && rc != Z_BUF_ERROR)
            m.refuse(rc);
    }
    return n - m.z.avail_out;
}

void ByteSource::finish()
{
    Impl& m = *mImpl;
    if (!m.compressed) return;
    // read() refuses a cut stream, a failed check and foreign trailing bytes;
    // here the rest is only inflated and discarded.
    std::vector<char> discard(1 << 16);
    while (!m.zEnd) (void)read(discard.data(), discard.size());
}

} // namespace voxhap::volume
