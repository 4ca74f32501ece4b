// SPDX-License-Identifier: Apache-2.0
/// @file FuzzNrrdHeader.cpp
/// @brief libFuzzer target: the hand-written NRRD header parser.

#include "FuzzInput.h"

#include "volume/NrrdHeader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    const std::string file = "fuzz.nrrd";
    try {
        voxhap::volume::parseNrrdHeader(std::string_view(reinterpret_cast<const char*>(data), size), file);
    } catch (const voxhap::Error& e) {
        voxhap::fuzz::checkRefusal(e, file);
    }
    return 0;
}
