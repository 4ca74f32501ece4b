// SPDX-License-Identifier: Apache-2.0
/// @file DicomNative.h
/// @brief Check the loader's uncompressed fast path (readNativeFrames) against
/// GDCM's decode of the same files.
#pragma once

#include "volume/dicom/DicomHeaders.h"
#include "volume/dicom/detail/DicomPixels.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <vector>

namespace voxhap::test {

/// The uncompressed fast path against GDCM's decode, byte for byte.
inline void expectNativeEqualsGdcm(const std::vector<std::filesystem::path>& inputs)
{
    std::vector<volume::DicomHeader> headers = volume::scanDicomHeaders(inputs);
    ASSERT_FALSE(headers.empty());
    for (volume::DicomHeader& h : headers) {
        volume::completeDicomHeader(h);
        volume::DicomFrames native;
        ASSERT_TRUE(volume::readNativeFrames(h, native))
            << h.file << ": not read natively (" << h.transferSyntax << ")";
        const volume::DicomFrames gdcm = volume::decodeDicomFrames(h.file);
        EXPECT_EQ(native.type, gdcm.type) << h.file;
        EXPECT_EQ(native.bitsStored, gdcm.bitsStored) << h.file;
        EXPECT_EQ(native.rows, gdcm.rows) << h.file;
        EXPECT_EQ(native.columns, gdcm.columns) << h.file;
        EXPECT_TRUE(native.raw == gdcm.raw) << h.file << ": samples differ from GDCM's decode";
    }
}

} // namespace voxhap::test
