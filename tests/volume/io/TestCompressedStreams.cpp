// SPDX-License-Identifier: Apache-2.0
/// @file TestCompressedStreams.cpp
/// @brief Issue 20 item 2: gzip and zlib voxel data in NRRD, MetaImage and
/// .nii.gz is verified to its end. Every file here is built by the test itself
/// with zlib (deflate, crc32, adler32), never by voxhap's writers, and every
/// loaded voxel is compared with the values the test put in. Each byte class is
/// damaged in turn: the deflate body, the CRC-32 / Adler-32, ISIZE, the file
/// cut at each part, bytes after the stream, and a second gzip member (which
/// is decoded, RFC 1952 §2.2). Then every byte of each stream is flipped once:
/// the file must be refused or load exactly the same voxels.

#include "common/TempDirTest.h"

#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/io/MetaImageFile.h"
#include "volume/io/NiftiFile.h"
#include "volume/io/NrrdFile.h"

#include <gtest/gtest.h>
#include <nifti1.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <functional>
#include <ostream>
#include <string>

namespace {

namespace fs = std::filesystem;
using namespace voxhap::volume;

constexpr int kNx = 13, kNy = 11, kNz = 9; // not multiples of the 8-voxel leaf

/// Stored value at (i, j, k): air (below the -950 HU threshold) on the i = 0
/// face, varied elsewhere so that a wrong byte anywhere shows.
std::int16_t stored(int i, int j, int k)
{
    return i == 0 ? std::int16_t(-1000) : std::int16_t(-700 + 53 * i + 29 * j - 17 * k + (i * j * k) % 7);
}

/// The samples, int16 little endian, x fastest.
std::string samples()
{
    std::string out;
    for (int k = 0; k < kNz; ++k)
        for (int j = 0; j < kNy; ++j)
            for (int i = 0; i < kNx; ++i) {
                const auto v = std::uint16_t(stored(i, j, k));
                out += char(v & 0xff);
                out += char(v >> 8);
            }
    return out;
}

/// @p data deflated inside the wrapper zlib writes for @p windowBits
/// (15 + 16: a gzip member, 10-byte header; 15: a zlib stream).
std::string deflateWith(const std::string& data, int windowBits)
{
    z_stream z{};
    EXPECT_EQ(deflateInit2(&z, 6, Z_DEFLATED, windowBits, 8, Z_DEFAULT_STRATEGY), Z_OK);
    std::string out(deflateBound(&z, uLong(data.size())) + 32, '\0');
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
    z.avail_in = uInt(data.size());
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = uInt(out.size());
    EXPECT_EQ(deflate(&z, Z_FINISH), Z_STREAM_END);
    out.resize(z.total_out);
    deflateEnd(&z);
    return out;
}

std::string gzipMember(const std::string& data) { return deflateWith(data, 15 + 16); }
std::string zlibStream(const std::string& data) { return deflateWith(data, 15); }

std::uint32_t le32(const std::string& s, std::size_t at)
{
    std::uint32_t v = 0;
    for (int b = 3; b >= 0; --b) v = v << 8 | std::uint8_t(s[at + std::size_t(b)]);
    return v;
}

/// One format under test: how a compressed stream becomes a file, and how the
/// file loads.
struct Format {
    std::string name; ///< file name, with the extension the reader expects
    bool gzip;        ///< gzip members (else one zlib stream)
    /// The bytes before the stream (empty for .nii.gz: the whole file is the stream)
    std::function<std::string(std::size_t streamBytes)> header;
    /// What is compressed: the samples, or for .nii.gz a NIfTI header and the samples
    std::function<std::string()> payload;
    std::function<Volume(const fs::path&)> load;
};

std::string nrrdHeader(std::size_t)
{
    return "NRRD0004\ntype: short\ndimension: 3\nspace: left-posterior-superior\nsizes: " + std::to_string(kNx) + " " +
        std::to_string(kNy) + " " + std::to_string(kNz) +
        "\nspace directions: (0.75,0,0) (0,0.8,0) (0,0,2.5)\nkinds: domain domain domain\nendian: little\n"
        "encoding: gzip\nspace origin: (-20,-30,10)\n\n";
}

std::string metaImageHeader(std::size_t streamBytes)
{
    return "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
           "CompressedData = True\nCompressedDataSize = " +
        std::to_string(streamBytes) +
        "\nTransformMatrix = 1 0 0 0 1 0 0 0 1\nOffset = -20 -30 10\n"
        "ElementSpacing = 0.75 0.8 2.5\nDimSize = " +
        std::to_string(kNx) + " " + std::to_string(kNy) + " " + std::to_string(kNz) +
        "\nElementType = MET_SHORT\nElementDataFile = LOCAL\n";
}

/// A NIfTI-1 single file (header, 4 bytes of empty extension flag, samples),
/// its header filled field by field from nifti1.h.
std::string niftiPayload()
{
    nifti_1_header h;
    std::memset(&h, 0, sizeof h);
    h.sizeof_hdr = 348;
    h.dim[0] = 3, h.dim[1] = kNx, h.dim[2] = kNy, h.dim[3] = kNz;
    for (int a = 4; a < 8; ++a) h.dim[a] = 1;
    h.datatype = DT_INT16;
    h.bitpix = 16;
    h.pixdim[0] = 1, h.pixdim[1] = 0.75f, h.pixdim[2] = 0.8f, h.pixdim[3] = 2.5f;
    h.vox_offset = 352;
    h.xyzt_units = NIFTI_UNITS_MM;
    h.sform_code = NIFTI_XFORM_SCANNER_ANAT;
    h.srow_x[0] = -0.75f, h.srow_x[3] = 20; // RAS: LPS x and y negated
    h.srow_y[1] = -0.8f, h.srow_y[3] = 30;
    h.srow_z[2] = 2.5f, h.srow_z[3] = 10;
    std::memcpy(h.magic, "n+1", 4);
    std::string out(reinterpret_cast<const char*>(&h), sizeof h);
    out += std::string(4, '\0');
    return out + samples();
}

/// The format's file name in test names and messages, not its bytes.
void PrintTo(const Format& f, std::ostream* os) { *os << f.name; }

std::vector<Format> formats()
{
    return {
        {"nrrd-gzip.nrrd", true, nrrdHeader, samples, [](const fs::path& p) { return loadNrrd(p); }},
        {"mha-zlib.mha", false, metaImageHeader, samples, [](const fs::path& p) { return loadMetaImage(p); }},
        // MetaImage readers (ITK's MetaIO) accept gzip-wrapped data too.
        {"mha-gzip.mha", true, metaImageHeader, samples, [](const fs::path& p) { return loadMetaImage(p); }},
        {"nii-gzip.nii.gz", true, [](std::size_t) { return std::string(); }, niftiPayload,
            [](const fs::path& p) { return loadNifti(p); }},
    };
}

/// The loaded volume holds exactly the stored values (air inactive); the first
/// difference as text, empty when none.
std::string differences(const Volume& v)
{
    if (v.indexBox().dims() != voxhap::Vec3i(kNx, kNy, kNz)) return "dimensions differ";
    auto acc = huGrid(v)->getConstAccessor();
    for (int k = 0; k < kNz; ++k)
        for (int j = 0; j < kNy; ++j)
            for (int i = 0; i < kNx; ++i) {
                const openvdb::Coord c(i, j, k);
                const bool air = stored(i, j, k) < -950;
                const float want = air ? kAirHu : float(stored(i, j, k));
                if (acc.getValue(c) != want || acc.isValueOn(c) == air) {
                    return "voxel (" + std::to_string(i) + ", " + std::to_string(j) + ", " + std::to_string(k) +
                        ") is " + std::to_string(acc.getValue(c)) + ", stored " + std::to_string(stored(i, j, k));
                }
            }
    return {};
}

class CompressedStreams : public voxhap::test::TempDirTest, public testing::WithParamInterface<Format> {
protected:
    void SetUp() override
    {
        TempDirTest::SetUp();
        const Format& f = GetParam();
        mPayload = f.payload();
        mStream = f.gzip ? gzipMember(mPayload) : zlibStream(mPayload);
        // The layout the byte classes below rely on, checked against zlib's
        // own checksums rather than assumed.
        if (f.gzip) {
            ASSERT_EQ(std::uint8_t(mStream[3]), 0) << "no optional gzip header fields: the header is 10 bytes";
            ASSERT_EQ(le32(mStream, mStream.size() - 8),
                crc32(0, reinterpret_cast<const Bytef*>(mPayload.data()), uInt(mPayload.size())));
            ASSERT_EQ(le32(mStream, mStream.size() - 4), mPayload.size());
        } else {
            const uLong a = adler32(1, reinterpret_cast<const Bytef*>(mPayload.data()), uInt(mPayload.size()));
            const std::string tail = mStream.substr(mStream.size() - 4);
            ASSERT_EQ(tail, std::string({char(a >> 24), char(a >> 16), char(a >> 8), char(a)}));
        }
        mHeader = f.header(mStream.size());
        mPath = mDir / f.name;
    }

    /// Write the header and @p stream; the byte offset of the stream in the file is mHeader.size().
    const fs::path& write(const std::string& stream) const
    {
        std::ofstream(mPath, std::ios::binary | std::ios::trunc) << mHeader << stream;
        return mPath;
    }
    /// The file of @p stream loads with exactly the stored voxels.
    void expectLoads(const std::string& stream, const std::string& what) const
    {
        try {
            EXPECT_EQ(differences(GetParam().load(write(stream))), "") << what;
        } catch (const voxhap::Error& e) {
            ADD_FAILURE() << what << ": refused: " << e.what();
        }
    }
    /// The file of @p stream is refused with one line naming the file, the
    /// "data" field and every part of @p parts (a checksum's name, a byte offset).
    void expectRefused(const std::string& stream, const std::vector<std::string>& parts, const std::string& what) const
    {
        try {
            const Volume v = GetParam().load(write(stream));
            ADD_FAILURE() << what << ": loaded (" << (differences(v).empty() ? "same voxels" : differences(v)) << ")";
        } catch (const voxhap::IoError& e) {
            const std::string m = e.what();
            EXPECT_EQ(m.rfind(mPath.string() + ": data: ", 0), 0u) << what << ": " << m;
            EXPECT_EQ(m.find('\n'), std::string::npos) << what << ": " << m;
            for (const auto& p : parts)
                EXPECT_NE(m.find(p), std::string::npos) << what << ": no '" << p << "' in " << m;
        }
    }
    /// "at byte N" / "byte N" for the file offset of stream byte @p at.
    std::string byte(std::size_t at) const { return "byte " + std::to_string(mHeader.size() + at); }

    std::string mPayload, mStream, mHeader;
    fs::path mPath;
};

TEST_P(CompressedStreams, IntactStreamLoadsTheStoredVoxels) { expectLoads(mStream, "intact"); }

TEST_P(CompressedStreams, FlipInTheDeflateBodyIsRefused)
{
    const std::size_t body = GetParam().gzip ? 10 : 2, trailer = GetParam().gzip ? 8 : 4;
    for (std::size_t at : {body + 1, (mStream.size() - trailer + body) / 2, mStream.size() - trailer - 2}) {
        std::string s = mStream;
        s[at] = char(s[at] ^ 0x10);
        expectRefused(s, {"data: "}, "flip at stream byte " + std::to_string(at));
    }
}

TEST_P(CompressedStreams, FlipInTheChecksumIsRefusedNamingItAndItsOffset)
{
    const bool gz = GetParam().gzip;
    const std::size_t field = mStream.size() - (gz ? 8 : 4);
    for (std::size_t b = 0; b < 4; ++b) {
        std::string s = mStream;
        s[field + b] = char(s[field + b] ^ (1 << b));
        expectRefused(s, {gz ? "CRC-32" : "Adler-32", "at " + byte(field)}, "checksum byte " + std::to_string(b));
    }
}

/// The gzip formats alone: a zlib stream stores no length to check.
class GzipStreams : public CompressedStreams { };

TEST_P(GzipStreams, FlipInTheStoredLengthIsRefusedNamingItAndItsOffset)
{
    ASSERT_TRUE(GetParam().gzip);
    const std::size_t field = mStream.size() - 4;
    for (std::size_t b = 0; b < 4; ++b) {
        std::string s = mStream;
        s[field + b] = char(s[field + b] ^ 0x80);
        expectRefused(s, {"ISIZE", "at " + byte(field)}, "ISIZE byte " + std::to_string(b));
    }
}

TEST_P(CompressedStreams, CutStreamIsRefusedAsTruncatedAtTheFileEnd)
{
    const std::size_t trailer = GetParam().gzip ? 8 : 4;
    // In the body, just before the trailer, inside the checksum, one byte short.
    for (std::size_t keep :
        {mStream.size() / 2, mStream.size() - trailer, mStream.size() - trailer + 2, mStream.size() - 1}) {
        expectRefused(mStream.substr(0, keep), {"truncated", byte(keep)}, "cut to " + std::to_string(keep) + " bytes");
    }
}

TEST_P(CompressedStreams, BytesAfterTheStreamAreRefused)
{
    // Text, a lone zero, a lone first magic byte, and an incomplete member header.
    for (const std::string& extra :
        {std::string("garbage"), std::string(1, '\0'), std::string("\x1f"), std::string("\x1f\x8b\x08", 3)}) {
        expectRefused(mStream + extra, {"byte "}, "followed by " + std::to_string(extra.size()) + " bytes");
    }
    // The reported offset is where the foreign bytes start.
    expectRefused(mStream + "garbage", {byte(mStream.size())}, "offset of trailing text");
}

TEST_P(CompressedStreams, SecondGzipMemberIsDecodedAsPartOfTheStream)
{
    if (!GetParam().gzip) {
        // A zlib stream has no members: a second stream, or a gzip member, after it is refused.
        const std::string half = mPayload.substr(0, mPayload.size() / 2);
        const std::string first = zlibStream(half);
        expectRefused(
            first + zlibStream(mPayload.substr(half.size())), {"zlib", "at " + byte(first.size())}, "zlib + zlib");
        expectRefused(mStream + gzipMember("x"), {"zlib"}, "zlib + gzip member");
        return;
    }
    // The payload split in two members at an odd place: the voxels must be whole.
    const std::size_t cut = mPayload.size() / 3 + 1;
    const std::string two = gzipMember(mPayload.substr(0, cut)) + gzipMember(mPayload.substr(cut));
    mHeader = GetParam().header(two.size());
    expectLoads(two, "two members");
    // An empty member after the data is a member like any other.
    mHeader = GetParam().header(mStream.size() + gzipMember("").size());
    expectLoads(mStream + gzipMember(""), "an empty member after");
    // A good member then a damaged one: the damage in the second is found.
    std::string second = gzipMember(mPayload.substr(cut));
    second[second.size() - 8] = char(second[second.size() - 8] ^ 1);
    const std::string first = gzipMember(mPayload.substr(0, cut));
    mHeader = GetParam().header(first.size() + second.size());
    expectRefused(first + second, {"CRC-32", "at " + byte(first.size() + second.size() - 8)}, "second member's CRC");
}

TEST_P(CompressedStreams, EveryByteFlippedIsRefusedOrLoadsTheSameVoxels)
{
    // One bit of every third byte in turn (bit = position mod 8, so every bit
    // position comes up; every byte would take seconds per format). CRC-32 and
    // Adler-32 catch every single-bit change of the inflated data, and the
    // trailer fields cover themselves. What may still load is a flip that
    // leaves the inflated bytes as they were: the gzip header's MTIME, XFL and
    // OS, padding bits after the final block, or a match whose changed
    // distance copies the same bytes (runs of zeros in a NIfTI header). Those
    // must load exactly the stored voxels, and stay rare.
    std::size_t accepted = 0;
    for (std::size_t at = 0; at < mStream.size(); at += 3) {
        std::string s = mStream;
        s[at] = char(s[at] ^ (1 << (at % 8)));
        try {
            const Volume v = GetParam().load(write(s));
            ASSERT_EQ(differences(v), "") << "flip at stream byte " << at << " loaded different voxels";
            ++accepted;
        } catch (const voxhap::IoError& e) {
            const std::string m = e.what();
            ASSERT_EQ(m.rfind(mPath.string() + ": ", 0), 0u) << m;
            ASSERT_EQ(m.find('\n'), std::string::npos) << m;
        }
    }
    EXPECT_LT(accepted, 8u) << "of " << mStream.size() / 3 << " flipped bytes";
    // Every flip in the trailer is refused, whatever the body.
    for (std::size_t at = mStream.size() - (GetParam().gzip ? 8 : 4); at < mStream.size(); ++at) {
        std::string s = mStream;
        s[at] = char(s[at] ^ (1 << (at % 8)));
        expectRefused(s, {"data: "}, "trailer flip at stream byte " + std::to_string(at));
    }
}

std::string formatName(const testing::TestParamInfo<Format>& p)
{
    std::string n = p.param.name.substr(0, p.param.name.find('.'));
    for (char& c : n) c = c == '-' ? '_' : c;
    return n;
}

std::vector<Format> gzipFormats()
{
    std::vector<Format> out;
    for (const Format& f : formats()) {
        if (f.gzip) out.push_back(f);
    }
    return out;
}

INSTANTIATE_TEST_SUITE_P(Formats, CompressedStreams, testing::ValuesIn(formats()), formatName);
INSTANTIATE_TEST_SUITE_P(Formats, GzipStreams, testing::ValuesIn(gzipFormats()), formatName);

} // namespace
