// SPDX-License-Identifier: Apache-2.0
/// @file TestNiftiFile.cpp
/// @brief NIfTI files written here with niftilib (oblique sform, qform only,
/// gzip, scaled int16) read back in LPS with exact values; an sform and a qform
/// that disagree resolved by the documented precedence; bad files refused with
/// one message naming the file and the field.

#include "common/TempDirTest.h"
#include "common/Tolerances.h"

#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/io/NiftiFile.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <nifti2_io.h>

#include <cstddef>
#include <cstring>
#include <fstream>
#include <limits>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

namespace {

namespace fs = std::filesystem;
using voxhap::Mat3d;
using voxhap::Vec3d;
using namespace voxhap::volume;

/// NIfTI-1 stores srow and the quaternion as float32: ~6e-6 mm of rounding on
/// coordinates of ~100 mm, and the quaternion's rotation is recomputed from
/// three floats. 1e-4 mm is well above that and far below a voxel.
constexpr double kNiftiFloatMm = 1e-4;

class Nifti : public voxhap::test::TempDirTest {
protected:
    void SetUp() override
    {
        TempDirTest::SetUp();
        nifti_set_debug_level(0);
    }

    static constexpr int kNx = 10, kNy = 7, kNz = 9;
    static float value(int i, int j, int k) { return i == 0 ? -1000.0f : float(-500 + 29 * i + 13 * j + 7 * k) + 0.5f; }

    /// An oblique ijk → RAS map: rotation × diag(spacing), then an offset.
    static Eigen::Matrix4d rasMatrix()
    {
        const Mat3d r = (Eigen::AngleAxisd(0.5, Vec3d(1, 2, 3).normalized())).toRotationMatrix();
        Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
        m.topLeftCorner<3, 3>() = r * Vec3d(0.8, 1.1, 2.0).asDiagonal();
        m.topRightCorner<3, 1>() = Vec3d(30.5, -72.25, 15.0);
        return m;
    }

    /// Write a float volume with the given transform fields set.
    fs::path write(const std::string& name, bool sform, bool qform) const
    {
        const int64_t dims[8] = {3, kNx, kNy, kNz, 1, 1, 1, 1};
        nifti_image* nim = nifti_make_new_nim(dims, DT_FLOAT32, 1);
        float* data = static_cast<float*>(nim->data);
        for (int k = 0; k < kNz; ++k)
            for (int j = 0; j < kNy; ++j)
                for (int i = 0; i < kNx; ++i) data[(k * kNy + j) * kNx + i] = value(i, j, k);
        const Eigen::Matrix4d m = rasMatrix();
        nifti_dmat44 mat;
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) mat.m[r][c] = m(r, c);
        nim->sform_code = sform ? NIFTI_XFORM_SCANNER_ANAT : 0;
        nim->sto_xyz = mat;
        nim->qform_code = qform ? NIFTI_XFORM_SCANNER_ANAT : 0;
        nifti_dmat44_to_quatern(mat, &nim->quatern_b, &nim->quatern_c, &nim->quatern_d, &nim->qoffset_x,
            &nim->qoffset_y, &nim->qoffset_z, &nim->dx, &nim->dy, &nim->dz, &nim->qfac);
        nim->pixdim[1] = nim->dx;
        nim->pixdim[2] = nim->dy;
        nim->pixdim[3] = nim->dz;
        const fs::path p = mDir / name;
        nifti_set_filenames(nim, p.string().c_str(), 0, 1);
        nifti_image_write(nim);
        nifti_image_free(nim);
        return p;
    }

    void expectLoadedInLps(const fs::path& p) const
    {
        const Volume v = loadNifti(p);
        EXPECT_EQ(v.indexBox().dims(), voxhap::Vec3i(kNx, kNy, kNz));
        const Eigen::Matrix4d m = rasMatrix();
        for (const Vec3d& ijk : {Vec3d(0, 0, 0), Vec3d(kNx - 1, 0, 0), Vec3d(3, kNy - 1, kNz - 1)}) {
            const Vec3d ras = (m * ijk.homogeneous()).head<3>();
            const Vec3d lps(-ras.x(), -ras.y(), ras.z());
            EXPECT_TRUE(voxhap::test::nearVec(v.indexToWorld(ijk), lps, kNiftiFloatMm)) << ijk.transpose();
        }
        auto acc = huGrid(v)->getConstAccessor();
        for (int k = 0; k < kNz; ++k)
            for (int j = 0; j < kNy; ++j)
                for (int i = 1; i < kNx; ++i)
                    ASSERT_EQ(acc.getValue(openvdb::Coord(i, j, k)), value(i, j, k)) << i << j << k;
        EXPECT_FALSE(acc.isValueOn(openvdb::Coord(0, 3, 3))) << "air is inactive";
    }
    /// Load @p p expecting an IoError whose one-line message names the file and contains @p field.
    static void expectRefused(const fs::path& p, const std::string& field, const RasterOptions& o = {})
    {
        voxhap::test::expectRefused<voxhap::IoError>([&](const fs::path& f) { loadNifti(f, o); }, p, field);
    }
};

TEST_F(Nifti, ObliqueSformReadsInLps) { expectLoadedInLps(write("sform.nii", true, false)); }

TEST_F(Nifti, QformAloneReadsInLps) { expectLoadedInLps(write("qform.nii", false, true)); }

TEST_F(Nifti, GzipFileReadsTheSame) { expectLoadedInLps(write("both.nii.gz", true, true)); }

TEST_F(Nifti, ScaledIntegersBecomeExactValues)
{
    const int64_t dims[8] = {3, 4, 3, 2, 1, 1, 1, 1};
    nifti_image* nim = nifti_make_new_nim(dims, DT_INT16, 1);
    auto* data = static_cast<std::int16_t*>(nim->data);
    for (int n = 0; n < 24; ++n) data[n] = std::int16_t(100 * n);
    nim->scl_slope = 2.0;
    nim->scl_inter = -1024.0;
    const fs::path p = mDir / "scaled.nii";
    nifti_set_filenames(nim, p.string().c_str(), 0, 1);
    nifti_image_write(nim);
    nifti_image_free(nim);
    const Volume v = loadNifti(p);
    auto acc = huGrid(v)->getConstAccessor();
    EXPECT_EQ(acc.getValue(openvdb::Coord(3, 2, 1)), 2.0f * 100 * 23 - 1024.0f);
    EXPECT_EQ(acc.getValue(openvdb::Coord(1, 0, 0)), 2.0f * 100 - 1024.0f);
    EXPECT_EQ(v.metadata().extra.at("nifti_transform"), "pixdim (no orientation in the file)");
}

TEST_F(Nifti, BadFilesAreRefusedNamingTheField)
{
    const fs::path good = write("good.nii", true, false);
    const auto copy = [&](const std::string& name, std::size_t keep, std::size_t patchAt = 0,
                          const std::string& patch = {}) {
        std::ifstream in(good, std::ios::binary);
        std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        bytes.resize(std::min(bytes.size(), keep));
        if (!patch.empty()) bytes.replace(patchAt, patch.size(), patch);
        std::ofstream(mDir / name, std::ios::binary) << bytes;
        return mDir / name;
    };
    expectRefused(copy("short-data.nii", fs::file_size(good) - 40), "data");
    expectRefused(copy("short-header.nii", 200), "header");
    expectRefused(copy("magic.nii", 1 << 20, 344, std::string("xx1\0", 4)), "magic");
    // dim[] (int16 at offset 40) = {4, 10, 7, 9, 2}: a time series of two volumes.
    expectRefused(copy("4d.nii", 1 << 20, 40, std::string("\x04\x00\x0a\x00\x07\x00\x09\x00\x02\x00", 10)), "dim");
    RasterOptions small;
    small.memoryCapBytes = 1000; // 10×7×9 floats = 2520 bytes
    expectRefused(good, "memory cap", small);
}

/// NIfTI-1 §"3 methods": a file may carry a qform and an sform that disagree.
/// voxhap's documented precedence (NiftiFile.h, docs/reference.md "Loading real data") is
/// the sform when sform_code > 0, else the qform when qform_code > 0.
class NiftiFrames : public Nifti {
protected:
    /// An axis-aligned qform far from rasMatrix(): spacing 1.5, 0.9, 2.5 mm and
    /// another offset, so that the two frames put every voxel centimetres apart.
    static Eigen::Matrix4d qformMatrix()
    {
        Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
        m.topLeftCorner<3, 3>() = Vec3d(1.5, 0.9, 2.5).asDiagonal();
        m.topRightCorner<3, 1>() = Vec3d(-60.0, 40.0, -25.0);
        return m;
    }

    /// A float volume whose sform is rasMatrix() and whose qform is qformMatrix(),
    /// both codes set; then sform_code (int16 at its offset in nifti_1_header)
    /// patched to @p sformCode, leaving the srow rows in place.
    fs::path writeDisagreeing(const std::string& name, std::int16_t sformCode) const
    {
        const int64_t dims[8] = {3, kNx, kNy, kNz, 1, 1, 1, 1};
        nifti_image* nim = nifti_make_new_nim(dims, DT_FLOAT32, 1);
        float* data = static_cast<float*>(nim->data);
        for (int k = 0; k < kNz; ++k)
            for (int j = 0; j < kNy; ++j)
                for (int i = 0; i < kNx; ++i) data[(k * kNy + j) * kNx + i] = value(i, j, k);
        const auto toNifti = [](const Eigen::Matrix4d& m) {
            nifti_dmat44 mat;
            for (int r = 0; r < 4; ++r)
                for (int c = 0; c < 4; ++c) mat.m[r][c] = m(r, c);
            return mat;
        };
        nim->sform_code = NIFTI_XFORM_SCANNER_ANAT;
        nim->sto_xyz = toNifti(rasMatrix());
        nim->qform_code = NIFTI_XFORM_SCANNER_ANAT;
        nifti_dmat44_to_quatern(toNifti(qformMatrix()), &nim->quatern_b, &nim->quatern_c, &nim->quatern_d,
            &nim->qoffset_x, &nim->qoffset_y, &nim->qoffset_z, &nim->dx, &nim->dy, &nim->dz, &nim->qfac);
        nim->pixdim[1] = nim->dx;
        nim->pixdim[2] = nim->dy;
        nim->pixdim[3] = nim->dz;
        const fs::path p = mDir / name;
        nifti_set_filenames(nim, p.string().c_str(), 0, 1);
        nifti_image_write(nim);
        nifti_image_free(nim);
        std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(std::streamoff(offsetof(nifti_1_header, sform_code)));
        f.write(reinterpret_cast<const char*>(&sformCode), sizeof sformCode); // little-endian, as written
        return p;
    }

    /// World positions of three corners of the grid under @p ras (ijk → RAS), in LPS.
    static void expectFrame(const Volume& v, const Eigen::Matrix4d& ras, const Eigen::Matrix4d& other)
    {
        for (const Vec3d& ijk : {Vec3d(0, 0, 0), Vec3d(kNx - 1, 0, 0), Vec3d(3, kNy - 1, kNz - 1)}) {
            const Vec3d a = (ras * ijk.homogeneous()).head<3>(), b = (other * ijk.homogeneous()).head<3>();
            ASSERT_GT((a - b).norm(), 10.0) << "the two frames must disagree for this test to mean anything";
            EXPECT_TRUE(voxhap::test::nearVec(v.indexToWorld(ijk), Vec3d(-a.x(), -a.y(), a.z()), kNiftiFloatMm))
                << ijk.transpose();
        }
    }
};

TEST_F(NiftiFrames, SformWinsWhenBothAreSetAndDisagree)
{
    const Volume v = loadNifti(writeDisagreeing("both.nii", NIFTI_XFORM_SCANNER_ANAT));
    expectFrame(v, rasMatrix(), qformMatrix());
    EXPECT_EQ(v.metadata().extra.at("nifti_transform"), "sform");
    EXPECT_NEAR(v.geometry().spacing.x(), 0.8, kNiftiFloatMm); // the sform's, not pixdim's 1.5
}

TEST_F(NiftiFrames, SformRowsAreIgnoredWhenItsCodeIsZero)
{
    const Volume v = loadNifti(writeDisagreeing("qform-wins.nii", 0));
    expectFrame(v, qformMatrix(), rasMatrix());
    EXPECT_EQ(v.metadata().extra.at("nifti_transform"), "qform");
}

TEST_F(Nifti, NanVoxelIsRefused)
{
    const int64_t dims[8] = {3, 2, 2, 2, 1, 1, 1, 1};
    nifti_image* nim = nifti_make_new_nim(dims, DT_FLOAT32, 1);
    static_cast<float*>(nim->data)[5] = std::numeric_limits<float>::quiet_NaN(); // voxel (1, 0, 1)
    const fs::path p = mDir / "nan.nii";
    nifti_set_filenames(nim, p.string().c_str(), 0, 1);
    nifti_image_write(nim);
    nifti_image_free(nim);
    expectRefused(p, "voxel (1, 0, 1) is not a finite number");
}

/// Issue 20 item 3: header fields niftilib would replace (vox_offset by 352,
/// a zero or NaN voxel size by 1 mm, a NaN slope by "unscaled") are refused,
/// naming the field.
class NiftiFields : public Nifti {
protected:
    /// The bytes of a good single-file NIfTI-1 (sform, positive pixdim) with
    /// @p patch written at @p at, saved as @p name (gzip if it ends in .gz).
    fs::path patched(const std::string& name, std::size_t at, const std::string& patch) const
    {
        const fs::path good = write("good-" + std::to_string(at) + ".nii", true, false);
        std::ifstream in(good, std::ios::binary);
        std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        bytes.replace(at, patch.size(), patch);
        const fs::path p = mDir / name;
        if (name.size() > 3 && name.compare(name.size() - 3, 3, ".gz") == 0) {
            gzFile gz = gzopen(p.c_str(), "wb");
            gzwrite(gz, bytes.data(), unsigned(bytes.size()));
            gzclose(gz);
        } else {
            std::ofstream(p, std::ios::binary) << bytes;
        }
        return p;
    }
    template <typename T> static std::string raw(T v)
    {
        return std::string(reinterpret_cast<const char*>(&v), sizeof v);
    }
    static constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
    static constexpr float kInf = std::numeric_limits<float>::infinity();
};

TEST_F(NiftiFields, VoxOffsetOutsideTheDataIsRefused)
{
    const std::size_t at = offsetof(nifti_1_header, vox_offset);
    expectRefused(patched("far.nii", at, raw(1e12f)),
        "vox_offset: " + std::to_string(std::uint64_t(1e12f)) + " is beyond the end of the file");
    expectRefused(patched("negative.nii", at, raw(-352.0f)), "vox_offset: -352 is negative");
    expectRefused(patched("nan.nii", at, raw(kNan)), "vox_offset: nan");
    expectRefused(patched("inf.nii", at, raw(kInf)), "vox_offset: inf");
    expectRefused(patched("header.nii", at, raw(348.0f)), "vox_offset: 348 lies inside the header");
    expectRefused(patched("zero.nii", at, raw(0.0f)), "vox_offset: 0 lies inside the header");
    expectRefused(patched("half.nii", at, raw(352.5f)), "vox_offset: 352.5 is not a whole number");
    // A .nii.gz against the decompressed length (10×7×9 floats after 352 bytes).
    expectRefused(patched("far.nii.gz", at, raw(4096.0f)), "vox_offset: 4096 is beyond the end of the decompressed");
    expectRefused(patched("header.nii.gz", at, raw(100.0f)), "vox_offset: 100 lies inside the header");
}

TEST_F(NiftiFields, BadVoxelSizesOnUsedAxesAreRefused)
{
    const std::size_t pixdim = offsetof(nifti_1_header, pixdim);
    expectRefused(patched("nan.nii", pixdim + 4 * 2, raw(kNan)), "pixdim: pixdim[2] = nan");
    expectRefused(patched("zero.nii", pixdim + 4 * 1, raw(0.0f)), "pixdim: pixdim[1] = 0");
    expectRefused(patched("negative.nii", pixdim + 4 * 3, raw(-2.0f)), "pixdim: pixdim[3] = -2");
    expectRefused(patched("inf.nii", pixdim + 4 * 3, raw(kInf)), "pixdim: pixdim[3] = inf");
    // pixdim[4] (time) is not a spatial axis: dim[4] = 1 there, and nothing reads it.
    EXPECT_NO_THROW(loadNifti(patched("time.nii", pixdim + 4 * 4, raw(kNan))));

    // On an axis of one voxel a zero size is no error (the sform gives the geometry).
    const int64_t dims[8] = {3, 4, 3, 1, 1, 1, 1, 1};
    nifti_image* nim = nifti_make_new_nim(dims, DT_FLOAT32, 1);
    nim->sform_code = NIFTI_XFORM_SCANNER_ANAT;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) nim->sto_xyz.m[r][c] = r == c ? 1.0 : 0.0;
    nim->pixdim[3] = nim->dz = 0.0f;
    const fs::path p = mDir / "slice.nii";
    nifti_set_filenames(nim, p.string().c_str(), 0, 1);
    nifti_image_write(nim);
    nifti_image_free(nim);
    EXPECT_EQ(loadNifti(p).indexBox().dims(), voxhap::Vec3i(4, 3, 1));
}

TEST_F(NiftiFields, BadDimsAreRefused)
{
    const std::size_t dim = offsetof(nifti_1_header, dim);
    expectRefused(patched("rank.nii", dim, raw(std::int16_t(8))), "dim: dim[0] = 8");
    expectRefused(patched("rank0.nii", dim, raw(std::int16_t(0))), "dim: dim[0] = 0");
    expectRefused(patched("zero.nii", dim + 2 * 2, raw(std::int16_t(0))), "dim: dim[2] = 0");
    expectRefused(patched("negative.nii", dim + 2 * 3, raw(std::int16_t(-9))), "dim: dim[3] = -9");
    std::string big = raw(std::int16_t(7));
    for (int a = 1; a <= 7; ++a) big += raw(std::int16_t(32767)); // 32767^7 × 4 bytes: beyond 2^63
    expectRefused(patched("overflow.nii", dim, big), "dim: the product dim[1]");
}

TEST_F(NiftiFields, NonFiniteScalingIsRefused)
{
    const std::size_t slope = offsetof(nifti_1_header, scl_slope), inter = offsetof(nifti_1_header, scl_inter);
    expectRefused(patched("nan.nii", slope, raw(kNan)), "scl_slope: nan");
    expectRefused(patched("inf.nii", slope, raw(-kInf)), "scl_slope: -inf");
    expectRefused(patched("inter.nii", slope, raw(2.0f) + raw(kInf)), "scl_inter: inf");
    // A slope of 0 means unscaled, whatever the intercept (NIfTI-1 standard).
    EXPECT_NO_THROW(loadNifti(patched("unscaled.nii", slope, raw(0.0f) + raw(kNan))));
    (void)inter;
}

TEST_F(NiftiFields, PairMayStartAtZeroButNotBeyondItsImage)
{
    const int64_t dims[8] = {3, 4, 3, 2, 1, 1, 1, 1};
    nifti_image* nim = nifti_make_new_nim(dims, DT_FLOAT32, 1);
    nim->nifti_type = NIFTI_FTYPE_NIFTI1_2;
    const fs::path hdr = mDir / "pair.hdr";
    nifti_set_filenames(nim, hdr.string().c_str(), 0, 1);
    nifti_image_write(nim);
    nifti_image_free(nim);
    ASSERT_TRUE(fs::exists(mDir / "pair.img"));
    EXPECT_EQ(loadNifti(hdr).indexBox().dims(), voxhap::Vec3i(4, 3, 2)); // vox_offset 0: valid in a pair
    const auto patchHeader = [&](float offset) {
        std::fstream f(hdr, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(std::streamoff(offsetof(nifti_1_header, vox_offset)));
        f.write(reinterpret_cast<const char*>(&offset), sizeof offset);
    };
    patchHeader(1e6f);
    expectRefused(hdr, "vox_offset: 1000000 is beyond the end of pair.img");
    patchHeader(-1.0f);
    expectRefused(hdr, "vox_offset: -1 is negative");
    patchHeader(0.0f);
    fs::remove(mDir / "pair.img");
    ASSERT_EQ(::mkfifo((mDir / "pair.img").c_str(), 0600), 0);
    expectRefused(hdr, "data file: pair.img is a FIFO");
}

TEST_F(NiftiFields, FifoOrDeviceIsRefusedUnopened)
{
    ASSERT_EQ(::mkfifo((mDir / "fifo.nii").c_str(), 0600), 0);
    expectRefused(mDir / "fifo.nii", "file type: a FIFO");
    fs::create_symlink("/dev/zero", mDir / "zero.nii.gz");
    expectRefused(mDir / "zero.nii.gz", "file type: a character device");
}

TEST_F(NiftiFields, Nifti2VoxOffsetAndDimsAreChecked)
{
    // Written by hand: niftilib 3 writes NIfTI-2 only through its own file naming.
    nifti_2_header h{};
    h.sizeof_hdr = 540;
    std::memcpy(h.magic, "n+2\0\r\n\032\n", 8);
    h.datatype = DT_FLOAT32;
    h.bitpix = 32;
    const std::int64_t dims[8] = {3, 4, 3, 2, 1, 1, 1, 1};
    for (int a = 0; a < 8; ++a) h.dim[a] = dims[a], h.pixdim[a] = 1.0;
    h.vox_offset = 544;
    const fs::path good = mDir / "two.nii";
    {
        std::ofstream out(good, std::ios::binary);
        out.write(reinterpret_cast<const char*>(&h), sizeof h);
        out << std::string(4 + 4 * 3 * 2 * 4, '\0'); // no extension; 24 zero floats
    }
    EXPECT_EQ(loadNifti(good).indexBox().dims(), voxhap::Vec3i(4, 3, 2));
    ASSERT_EQ(fs::file_size(good), 544u + 4 * 3 * 2 * 4) << "a NIfTI-2 file";
    std::ifstream in(good, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto variant = [&](const std::string& name, std::size_t at, const std::string& patch) {
        std::string b = bytes;
        b.replace(at, patch.size(), patch);
        std::ofstream(mDir / name, std::ios::binary) << b;
        return mDir / name;
    };
    const std::size_t voxOffset = offsetof(nifti_2_header, vox_offset), dim = offsetof(nifti_2_header, dim);
    expectRefused(variant("negative.nii", voxOffset, raw(std::int64_t(-544))), "vox_offset: -544 is negative");
    expectRefused(variant("inside.nii", voxOffset, raw(std::int64_t(540))), "vox_offset: 540 lies inside the header");
    expectRefused(variant("far.nii", voxOffset, raw(std::int64_t(1) << 40)), "vox_offset: 1099511627776 is beyond");
    expectRefused(variant("overflow.nii", dim + 8, raw(std::int64_t(1) << 62)), "dim: the product dim[1]");
}

} // namespace
