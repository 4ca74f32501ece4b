// SPDX-License-Identifier: Apache-2.0
/// @file FuzzMetaImageHeader.cpp
/// @brief libFuzzer target: the hand-written MetaImage header parser.

#include "FuzzInput.h"

#include "volume/MetaImageHeader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    const std::string file = "fuzz.mha";
    try {
        voxhap::volume::parseMetaImageHeader(std::string_view(reinterpret_cast<const char*>(data), size), file);
    } catch (const voxhap::Error& e) {
        voxhap::fuzz::checkRefusal(e, file);
    }
    return 0;
}
