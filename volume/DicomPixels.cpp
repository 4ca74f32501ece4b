// SPDX-License-Identifier: Apache-2.0
/// @file DicomPixels.cpp
/// @brief gdcm::ImageReader decoding with explicit length and format checks.

#include "volume/DicomPixels.h"

#include "volume/Errors.h"

#include <gdcmImageReader.h>
#include <gdcmTrace.h>

#include <cstring>
#include <fstream>
#include <mutex>
#include <string>

namespace voxhap::volume {

namespace {

/// Stored values → float. Unused high bits (BitsStored < BitsAllocated) may
/// hold overlays: mask them off, sign-extending signed data.
template <typename T>
void convert(const char* raw, std::size_t count, int bitsStored, float* out)
{
    constexpr int bits = int(sizeof(T) * 8);
    for (std::size_t n = 0; n < count; ++n) {
        T v;
        std::memcpy(&v, raw + n * sizeof(T), sizeof(T));
        if constexpr (std::is_integral_v<T> && sizeof(T) <= 4) {
            if (bitsStored > 0 && bitsStored < bits) {
                using U = std::make_unsigned_t<T>;
                const U mask = U((std::uint64_t(1) << bitsStored) - 1);
                U u = U(v) & mask;
                if constexpr (std::is_signed_v<T>) {
                    if (u & (U(1) << (bitsStored - 1))) u = U(u | U(~mask)); // sign-extend
                }
                v = T(u);
            }
        }
        out[n] = float(v);
    }
}

} // namespace

void quietGdcm()
{
    static std::once_flag once;
    std::call_once(once, [] {
        gdcm::Trace::SetDebug(false);
        gdcm::Trace::SetWarning(false);
        gdcm::Trace::SetError(false);
    });
}

DicomFrames decodeDicomFrames(const std::filesystem::path& file, std::optional<double> paddingValue)
{
    DicomFrames f;
    decodeDicomFrames(file, paddingValue, f);
    return f;
}

void decodeDicomFrames(const std::filesystem::path& file, std::optional<double> paddingValue, DicomFrames& f)
{
    quietGdcm();
    const std::string name = file.string();
    gdcm::ImageReader reader;
    reader.SetFileName(name.c_str());
    if (!reader.Read()) throw IoError(name + ": not a readable DICOM image (header or (7FE0,0010) PixelData)");
    const gdcm::Image& img = reader.GetImage();
    const gdcm::PixelFormat& pf = img.GetPixelFormat();
    // The header's syntax: the image's own may already be "corrected" by GDCM.
    const gdcm::TransferSyntax& ts = reader.GetFile().GetHeader().GetDataSetTransferSyntax();
    const std::string tsUid = ts.GetString() ? ts.GetString() : "?";
    // Video syntaxes (MPEG-2/4, HEVC: 1.2.840.10008.1.2.4.100 to .108) are not slice images.
    if (!ts.IsValid() || tsUid.rfind("1.2.840.10008.1.2.4.10", 0) == 0) {
        throw IoError(name + ": (0002,0010) TransferSyntaxUID " + tsUid + ": unsupported transfer syntax");
    }
    // A compressed syntax needs encapsulated pixel data; GDCM would read plain
    // bytes under it without a word, so the header and the data disagree.
    if (ts.IsEncapsulated() && !img.GetDataElement().GetSequenceOfFragments()) {
        throw IoError(name + ": (0002,0010) TransferSyntaxUID " + tsUid +
                      " is compressed but (7FE0,0010) PixelData is not encapsulated: inconsistent header");
    }
    if (pf.GetSamplesPerPixel() != 1) {
        throw IoError(name + ": (0028,0002) SamplesPerPixel is " + std::to_string(pf.GetSamplesPerPixel()) +
                      ": colour images are not volumes");
    }
    f.columns = int(img.GetDimension(0));
    f.rows = int(img.GetDimension(1));
    f.frames = img.GetNumberOfDimensions() > 2 ? int(img.GetDimension(2)) : 1;
    if (f.rows <= 0 || f.columns <= 0 || f.frames <= 0) throw IoError(name + ": (0028,0010) Rows / (0028,0011) Columns: empty image");

    const std::size_t count = std::size_t(f.rows) * std::size_t(f.columns) * std::size_t(f.frames);
    const std::size_t expected = img.GetBufferLength();
    // GDCM zero-fills a truncated uncompressed pixel element and only warns:
    // preflightDicom (run on every file before GDCM sees it) has checked that
    // the element fits in the file; here its declared length must cover the image.
    if (!ts.IsEncapsulated()) {
        const gdcm::ByteValue* bv = img.GetDataElement().GetByteValue();
        if (!bv || bv->GetLength() < expected) {
            throw IoError(name + ": (7FE0,0010) PixelData holds " + std::to_string(bv ? std::uint64_t(bv->GetLength()) : 0) +
                          " bytes, expected " + std::to_string(expected));
        }
    }
    std::vector<char>& raw = f.raw;
    raw.resize(expected);
    if (!img.GetBuffer(raw.data())) {
        throw IoError(name + ": (0002,0010) TransferSyntaxUID " + tsUid + ": cannot decode the pixel data (unsupported or corrupt)");
    }
    f.values.resize(count);
    const int bs = pf.GetBitsStored();
    switch (pf.GetScalarType()) {
    case gdcm::PixelFormat::UINT8: convert<std::uint8_t>(raw.data(), count, bs, f.values.data()); break;
    case gdcm::PixelFormat::INT8: convert<std::int8_t>(raw.data(), count, bs, f.values.data()); break;
    case gdcm::PixelFormat::UINT16: convert<std::uint16_t>(raw.data(), count, bs, f.values.data()); break;
    case gdcm::PixelFormat::INT16: convert<std::int16_t>(raw.data(), count, bs, f.values.data()); break;
    case gdcm::PixelFormat::UINT32: convert<std::uint32_t>(raw.data(), count, bs, f.values.data()); break;
    case gdcm::PixelFormat::INT32: convert<std::int32_t>(raw.data(), count, bs, f.values.data()); break;
    case gdcm::PixelFormat::FLOAT32: convert<float>(raw.data(), count, 0, f.values.data()); break;
    case gdcm::PixelFormat::FLOAT64: convert<double>(raw.data(), count, 0, f.values.data()); break;
    default:
        throw IoError(name + ": (0028,0100) BitsAllocated " + std::to_string(pf.GetBitsAllocated()) +
                      ": unsupported pixel type " + pf.GetScalarTypeAsString());
    }
    if (paddingValue) {
        // Compare in the stored domain, where the padding value is defined.
        f.padding.resize(count);
        const float pad = float(*paddingValue);
        for (std::size_t n = 0; n < count; ++n) f.padding[n] = f.values[n] == pad;
    } else {
        f.padding.clear();
    }
}

} // namespace voxhap::volume
