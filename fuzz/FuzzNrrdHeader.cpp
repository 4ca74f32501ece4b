// SPDX-License-Identifier: Apache-2.0
/// @file FuzzNrrdHeader.cpp
/// @brief libFuzzer target: the hand-written NRRD header parser.

#include "FuzzInput.h"

#include "volume/io/NrrdHeader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    return voxhap::fuzz::parseText(data, size, "fuzz.nrrd",
        [](std::string_view text, const std::string& file) { voxhap::volume::parseNrrdHeader(text, file); });
}
