// SPDX-License-Identifier: Apache-2.0
/// @file DicomPixels.cpp
/// @brief gdcm::ImageReader decoding with explicit length and format checks.

#include "volume/dicom/detail/DicomPixels.h"

#include "core/Errors.h"

#include <gdcmImageReader.h>
#include <gdcmTrace.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <mutex>
#include <string>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace voxhap::volume {

namespace {

/// Stored samples → rescaled floats in one pass. The value sits in bits
/// HighBit − BitsStored + 1 .. HighBit of each word (PS3.5 §8.1.1); the other
/// bits may hold overlays or garbage: the value is shifted down, masked and,
/// for signed data, sign-extended. The four variants keep the per-sample loop
/// branch-free.
template <typename T>
void toFloat(const char* raw, std::size_t count, int bitsStored, int shift, double slope, double intercept,
    std::optional<double> padding, float air, float* out)
{
    constexpr int bits = int(sizeof(T) * 8);
    const auto run = [&](auto masked, auto padded) {
        using U = std::make_unsigned_t<std::conditional_t<std::is_integral_v<T>, T, int>>;
        const U mask = U((std::uint64_t(1) << std::min(bitsStored, 63)) - 1);
        const U sign = U(U(1) << std::max(bitsStored - 1, 0));
        const double pad = padding.value_or(0.0);
        for (std::size_t n = 0; n < count; ++n) {
            T v;
            std::memcpy(&v, raw + n * sizeof(T), sizeof(T));
            if constexpr (decltype(masked)::value) {
                U u = U(U(v) >> shift) & mask;
                if constexpr (std::is_signed_v<T>) {
                    if (u & sign) u = U(u | U(~mask));
                }
                v = T(u);
            }
            const double d = double(v);
            if constexpr (decltype(padded)::value) {
                out[n] = d == pad ? air : float(slope * d + intercept);
            } else {
                out[n] = float(slope * d + intercept);
            }
        }
    };
    bool masked = false;
    if constexpr (std::is_integral_v<T> && sizeof(T) <= 4) masked = bitsStored > 0 && (bitsStored < bits || shift > 0);
    using Yes = std::true_type;
    using No = std::false_type;
    if constexpr (std::is_integral_v<T> && sizeof(T) <= 4) {
        if (masked) {
            padding ? run(Yes{}, Yes{}) : run(Yes{}, No{});
            return;
        }
    }
    padding ? run(No{}, Yes{}) : run(No{}, No{});
}

#if defined(__SSE2__)
/// toFloat for 16-bit samples, eight at a time: what CT and most MR store.
/// Bit for bit what the scalar toFloat gives (the tests compare them on
/// every real CT voxel): the same masking and sign extension; the rescale in
/// double (SSE2's mulpd, addpd and cvtpd2ps round as the scalar code does),
/// or, when the slope is 1 and the intercept an integer of at most 2^23, in
/// int32, whose sum (below 2^24 in magnitude) converts to float exactly, as
/// the double sum does; the padding value compared as the integer it must be
/// to equal a stored value. The last count mod 8 samples go to toFloat.
template <bool Signed>
void shortsToFloat(const char* raw, std::size_t count, int bitsStored, int shift, double slope, double intercept,
    std::optional<double> padding, float air, float* out)
{
    using T = std::conditional_t<Signed, std::int16_t, std::uint16_t>;
    const bool masked = bitsStored > 0 && (bitsStored < 16 || shift > 0);
    const __m128i mask = _mm_set1_epi16(short(std::uint16_t((std::uint64_t(1) << std::min(bitsStored, 63)) - 1)));
    const __m128i shiftBy = _mm_cvtsi32_si128(shift);
    const __m128i extendBy = _mm_cvtsi32_si128(bitsStored > 0 && bitsStored < 16 ? 16 - bitsStored : 0);
    const bool integer = slope == 1.0 && intercept == std::trunc(intercept) && std::abs(intercept) <= double(1 << 23);
    const __m128i interceptInt = _mm_set1_epi32(integer ? int(intercept) : 0);
    const __m128d slopeD = _mm_set1_pd(slope), interceptD = _mm_set1_pd(intercept);
    // A padding value that is not an integer in int32's range equals no 16-bit sample.
    const bool padded = padding && *padding == std::trunc(*padding) && std::abs(*padding) < 2147483648.0;
    const __m128i pad = _mm_set1_epi32(padded ? int(*padding) : 0);
    const __m128 airV = _mm_set1_ps(air);
    const auto finish = [&](__m128i v, float* o) {
        __m128 f;
        if (integer) {
            f = _mm_cvtepi32_ps(_mm_add_epi32(v, interceptInt));
        } else {
            const __m128 lo = _mm_cvtpd_ps(_mm_add_pd(_mm_mul_pd(_mm_cvtepi32_pd(v), slopeD), interceptD));
            const __m128 hi =
                _mm_cvtpd_ps(_mm_add_pd(_mm_mul_pd(_mm_cvtepi32_pd(_mm_shuffle_epi32(v, 0x4E)), slopeD), interceptD));
            f = _mm_movelh_ps(lo, hi);
        }
        if (padded) {
            const __m128 isPad = _mm_castsi128_ps(_mm_cmpeq_epi32(v, pad));
            f = _mm_or_ps(_mm_and_ps(isPad, airV), _mm_andnot_ps(isPad, f));
        }
        _mm_storeu_ps(o, f);
    };
    std::size_t n = 0;
    for (; n + 8 <= count; n += 8) {
        __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(raw + 2 * n));
        if (masked) {
            v = _mm_and_si128(_mm_srl_epi16(v, shiftBy), mask);
            if (Signed) v = _mm_sra_epi16(_mm_sll_epi16(v, extendBy), extendBy); // bit bitsStored-1 is the sign
        }
        // Widen to int32: zero-extended, or sign-extended (each word into the
        // high half of a lane, then shifted down arithmetically).
        const __m128i lo =
            Signed ? _mm_srai_epi32(_mm_unpacklo_epi16(v, v), 16) : _mm_unpacklo_epi16(v, _mm_setzero_si128());
        const __m128i hi =
            Signed ? _mm_srai_epi32(_mm_unpackhi_epi16(v, v), 16) : _mm_unpackhi_epi16(v, _mm_setzero_si128());
        finish(lo, out + n);
        finish(hi, out + n + 4);
    }
    if (n < count) toFloat<T>(raw + 2 * n, count - n, bitsStored, shift, slope, intercept, padding, air, out + n);
}
#endif

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

DicomFrames decodeDicomFrames(const std::filesystem::path& file)
{
    DicomFrames f;
    decodeDicomFrames(file, f);
    return f;
}

void decodeDicomFramesInProcess(const std::filesystem::path& file, DicomFrames& f)
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
    if (f.rows <= 0 || f.columns <= 0 || f.frames <= 0)
        throw IoError(name + ": (0028,0010) Rows / (0028,0011) Columns: empty image");

    const std::size_t count = std::size_t(f.rows) * std::size_t(f.columns) * std::size_t(f.frames);
    const std::size_t expected = img.GetBufferLength();
    // GDCM zero-fills a truncated uncompressed pixel element and only warns:
    // preflightDicom (run on every file before GDCM sees it) has checked that
    // the element fits in the file; here its declared length must cover the image.
    if (!ts.IsEncapsulated()) {
        const gdcm::ByteValue* bv = img.GetDataElement().GetByteValue();
        if (!bv || bv->GetLength() < expected) {
            throw IoError(name + ": (7FE0,0010) PixelData holds " +
                std::to_string(bv ? std::uint64_t(bv->GetLength()) : 0) + " bytes, expected " +
                std::to_string(expected));
        }
    }
    std::vector<char>& raw = f.raw;
    raw.resize(expected);
    if (!img.GetBuffer(raw.data())) {
        throw IoError(name + ": (0002,0010) TransferSyntaxUID " + tsUid +
            ": cannot decode the pixel data (unsupported or corrupt)");
    }
    f.bitsStored = pf.GetBitsStored();
    f.highBit = pf.GetHighBit();
    switch (pf.GetScalarType()) {
    case gdcm::PixelFormat::UINT8:
        f.type = SampleType::UInt8;
        break;
    case gdcm::PixelFormat::INT8:
        f.type = SampleType::Int8;
        break;
    case gdcm::PixelFormat::UINT16:
        f.type = SampleType::UInt16;
        break;
    case gdcm::PixelFormat::INT16:
        f.type = SampleType::Int16;
        break;
    case gdcm::PixelFormat::UINT32:
        f.type = SampleType::UInt32;
        break;
    case gdcm::PixelFormat::INT32:
        f.type = SampleType::Int32;
        break;
    case gdcm::PixelFormat::FLOAT32:
        f.type = SampleType::Float32;
        break;
    case gdcm::PixelFormat::FLOAT64:
        f.type = SampleType::Float64;
        break;
    default:
        throw IoError(name + ": (0028,0100) BitsAllocated " + std::to_string(pf.GetBitsAllocated()) +
            ": unsupported pixel type " + pf.GetScalarTypeAsString());
    }
    if (sampleBytes(f.type) * count != expected) {
        throw IoError(name + ": (0028,0100) BitsAllocated " + std::to_string(pf.GetBitsAllocated()) +
            ": the decoded buffer does not match the pixel type");
    }
}

bool nativeFrameLayout(const DicomHeader& h, DicomFrames& f)
{
    const bool littleEndian = h.transferSyntax == "1.2.840.10008.1.2" || h.transferSyntax == "1.2.840.10008.1.2.1";
    if (!littleEndian || h.pixelLength == 0 ||
        (h.bitsAllocated != 8 && h.bitsAllocated != 16 && h.bitsAllocated != 32)) {
        return false;
    }
    const bool sign = h.pixelRepresentation == 1;
    switch (h.bitsAllocated) {
    case 8:
        f.type = sign ? SampleType::Int8 : SampleType::UInt8;
        break;
    case 16:
        f.type = sign ? SampleType::Int16 : SampleType::UInt16;
        break;
    default:
        f.type = sign ? SampleType::Int32 : SampleType::UInt32;
        break;
    }
    f.rows = h.storedRows;
    f.columns = h.storedColumns;
    f.frames = h.storedFrames;
    f.bitsStored = h.bitsStored;
    f.highBit = h.highBit;
    const std::uint64_t expected =
        std::uint64_t(f.rows) * std::uint64_t(f.columns) * std::uint64_t(f.frames) * sampleBytes(f.type);
    if (h.pixelLength < expected) {
        throw IoError(h.file.string() + ": (7FE0,0010) PixelData holds " + std::to_string(h.pixelLength) +
            " bytes, expected " + std::to_string(expected));
    }
    return true;
}

bool readNativeFrames(const DicomHeader& h, DicomFrames& f)
{
    if (!nativeFrameLayout(h, f)) return false;
    const std::uint64_t expected =
        std::uint64_t(f.rows) * std::uint64_t(f.columns) * std::uint64_t(f.frames) * sampleBytes(f.type);
    f.raw.resize(expected);
    std::ifstream in(h.file, std::ios::binary);
    in.seekg(std::streamoff(h.pixelOffset));
    if (!in.read(f.raw.data(), std::streamsize(expected))) {
        throw IoError(h.file.string() + ": (7FE0,0010) PixelData: cannot read " + std::to_string(expected) + " bytes");
    }
    return true;
}

void frameToFloat(const DicomFrames& f, int frame, double slope, double intercept, std::optional<double> padding,
    float air, float* out)
{
    samplesToFloat(f, frame, 0, std::size_t(f.rows) * std::size_t(f.columns), slope, intercept, padding, air, out);
}

void samplesToFloat(const DicomFrames& f, int frame, std::size_t first, std::size_t plane, double slope,
    double intercept, std::optional<double> padding, float air, float* out)
{
    const std::size_t framePlane = std::size_t(f.rows) * std::size_t(f.columns);
    rawSamplesToFloat(f, f.raw.data() + (framePlane * std::size_t(frame) + first) * sampleBytes(f.type), plane, slope,
        intercept, padding, air, out);
}

void rawSamplesToFloat(const DicomFrames& f, const char* raw, std::size_t plane, double slope, double intercept,
    std::optional<double> padding, float air, float* out)
{
    // A HighBit outside bitsStored − 1 .. the word was refused with the header.
    const int shift = f.highBit < 0 ? 0 : std::max(0, f.highBit + 1 - f.bitsStored);
    switch (f.type) {
    case SampleType::UInt8:
        toFloat<std::uint8_t>(raw, plane, f.bitsStored, shift, slope, intercept, padding, air, out);
        break;
    case SampleType::Int8:
        toFloat<std::int8_t>(raw, plane, f.bitsStored, shift, slope, intercept, padding, air, out);
        break;
#if defined(__SSE2__)
    case SampleType::UInt16:
        shortsToFloat<false>(raw, plane, f.bitsStored, shift, slope, intercept, padding, air, out);
        break;
    case SampleType::Int16:
        shortsToFloat<true>(raw, plane, f.bitsStored, shift, slope, intercept, padding, air, out);
        break;
#else
    case SampleType::UInt16:
        toFloat<std::uint16_t>(raw, plane, f.bitsStored, shift, slope, intercept, padding, air, out);
        break;
    case SampleType::Int16:
        toFloat<std::int16_t>(raw, plane, f.bitsStored, shift, slope, intercept, padding, air, out);
        break;
#endif
    case SampleType::UInt32:
        toFloat<std::uint32_t>(raw, plane, f.bitsStored, shift, slope, intercept, padding, air, out);
        break;
    case SampleType::Int32:
        toFloat<std::int32_t>(raw, plane, f.bitsStored, shift, slope, intercept, padding, air, out);
        break;
    case SampleType::Float32:
        toFloat<float>(raw, plane, 0, 0, slope, intercept, padding, air, out);
        break;
    case SampleType::Float64:
        toFloat<double>(raw, plane, 0, 0, slope, intercept, padding, air, out);
        break;
    }
}

} // namespace voxhap::volume
