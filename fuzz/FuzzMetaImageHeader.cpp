// SPDX-License-Identifier: Apache-2.0
/// @file FuzzMetaImageHeader.cpp
/// @brief libFuzzer target: the hand-written MetaImage header parser.

#include "FuzzInput.h"

#include "volume/io/MetaImageHeader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    return voxhap::fuzz::parseText(data, size, "fuzz.mha",
        [](std::string_view text, const std::string& file) { voxhap::volume::parseMetaImageHeader(text, file); });
}
