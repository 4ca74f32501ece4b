// SPDX-License-Identifier: Apache-2.0
/// @file TestSampleConversion.cpp
/// @brief Stored DICOM samples to rescaled floats (samplesToFloat), checked
/// bit for bit against the rule written out here, one sample at a time, as
/// PS3.5 §8.1.1 and PS3.3 C.7.6.3.1 state it: the value sits in bits
/// HighBit - BitsStored + 1 .. HighBit, is sign-extended for signed data,
/// equals PixelPaddingValue or becomes slope * value + intercept (in double,
/// rounded once to float). The loader converts 16-bit samples eight at a time;
/// every mode of that (masking, sign, integer or real rescale, padding, a
/// count that is not a multiple of 8) is compared here.

#include "volume/dicom/detail/DicomPixels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace {

using namespace voxhap::volume;

/// The rule, for one 16-bit word.
float expected(std::uint16_t word, bool isSigned, int bitsStored, int highBit, double slope, double intercept,
    std::optional<double> padding, float air)
{
    const int low = highBit - bitsStored + 1;
    std::int64_t v = (word >> low) & ((1 << bitsStored) - 1);
    if (isSigned && (v >> (bitsStored - 1)) & 1) v -= std::int64_t(1) << bitsStored;
    if (padding && double(v) == *padding) return air;
    return float(slope * double(v) + intercept);
}

std::string bits(float f)
{
    std::uint32_t u;
    std::memcpy(&u, &f, 4);
    return std::to_string(f) + " (0x" +
        [&] {
            char b[9];
            std::snprintf(b, sizeof b, "%08x", u);
            return std::string(b);
        }() +
        ")";
}

TEST(SampleConversion, SixteenBitSamplesFollowTheRuleBitForBit)
{
    std::mt19937 random(20);
    std::vector<std::uint16_t> words(8 * 64 + 5); // 8 frames of 64, and a tail of 5
    for (auto& w : words) w = std::uint16_t(random());
    // Words that hit the edges: all bits, none, the sign bit of each width.
    words[0] = 0xffff, words[1] = 0, words[2] = 0x8000, words[3] = 0x0800, words[4] = 0x07ff, words[5] = 0x0fff;
    struct Rescale {
        double slope, intercept;
    };
    const std::vector<Rescale> rescales = {{1, 0}, {1, -1024}, {1, -1000}, {1, 8388608}, {1, -8388609}, {1, 0.5},
        {2, -1024}, {0.3333333333, -7.25}, {1e-3, 1e5}, {-1, 3}};
    const std::vector<std::optional<double>> paddings = {std::nullopt, -2000.0, 0.0, 4095.0, -1.0, 2.5, 1e12};
    std::int64_t compared = 0;
    for (bool isSigned : {false, true}) {
        for (int bitsStored : {16, 12, 10, 8}) {
            for (int highBit : {bitsStored - 1, 15}) {
                DicomFrames f;
                f.type = isSigned ? SampleType::Int16 : SampleType::UInt16;
                f.rows = 1;
                f.columns = int(words.size());
                f.frames = 1;
                f.bitsStored = bitsStored;
                f.highBit = highBit;
                f.raw.resize(words.size() * 2);
                std::memcpy(f.raw.data(), words.data(), f.raw.size()); // little-endian host, as the loader's
                for (const Rescale& r : rescales) {
                    for (const auto& pad : paddings) {
                        // From several starting samples: the eight-at-a-time loop meets
                        // every alignment and tail length.
                        for (std::size_t first : {std::size_t(0), std::size_t(3), std::size_t(8)}) {
                            const std::size_t count = words.size() - first;
                            std::vector<float> out(count);
                            samplesToFloat(f, 0, first, count, r.slope, r.intercept, pad, -3000.0f, out.data());
                            for (std::size_t n = 0; n < count; ++n) {
                                const float want = expected(words[first + n], isSigned, bitsStored, highBit, r.slope,
                                    r.intercept, pad, -3000.0f);
                                ASSERT_EQ(std::memcmp(&out[n], &want, 4), 0)
                                    << "word 0x" << std::hex << words[first + n] << std::dec << " signed " << isSigned
                                    << " bits " << bitsStored << " high " << highBit << " slope " << r.slope
                                    << " intercept " << r.intercept << " padding " << (pad ? *pad : -0.0) << ": "
                                    << bits(out[n]) << ", expected " << bits(want);
                                ++compared;
                            }
                        }
                    }
                }
            }
        }
    }
    EXPECT_GT(compared, 1000000);
}

} // namespace
