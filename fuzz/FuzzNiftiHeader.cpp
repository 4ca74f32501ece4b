// SPDX-License-Identifier: Apache-2.0
/// @file FuzzNiftiHeader.cpp
/// @brief libFuzzer target: voxhap's NIfTI header checks and niftilib's
/// header reader behind them (which reads from a path: a scratch file).

#include "FuzzInput.h"

#include "volume/io/NiftiHeader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    // gzip-compressed inputs go through the .nii.gz path (ByteSource and znz).
    static voxhap::fuzz::ScratchFile plain(".nii"), gzipped(".nii.gz");
    const bool gz = size >= 2 && data[0] == 0x1f && data[1] == 0x8b;
    const auto& file = (gz ? gzipped : plain).write(data, size);
    try {
        voxhap::volume::readNiftiHeader(file, std::uint64_t(1) << 30);
    } catch (const voxhap::Error& e) {
        voxhap::fuzz::checkRefusal(e, file.string());
    }
    return 0;
}
