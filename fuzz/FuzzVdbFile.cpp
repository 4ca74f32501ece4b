// SPDX-License-Identifier: Apache-2.0
/// @file FuzzVdbFile.cpp
/// @brief libFuzzer target: voxhap's .vdb loader end to end, the container
/// walk before OpenVDB and OpenVDB's readers behind it (from a scratch file).
/// A mutated file is refused with one line naming it, or loads; memory stays
/// bounded (an allocation over libFuzzer's -malloc_limit_mb is a finding).

#include "FuzzInput.h"

#include "volume/io/VdbFile.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    static voxhap::fuzz::ScratchFile scratch(".vdb");
    const auto& file = scratch.write(data, size);
    try {
        // a cap well under libFuzzer's limits: a grid over it must be refused, not allocated
        const voxhap::volume::Volume v = voxhap::volume::loadVdb(file, std::uint64_t(256) << 20);
        if (!v.has(voxhap::volume::Channel::Hu) && !v.has(voxhap::volume::Channel::T1) &&
            !v.has(voxhap::volume::Channel::Label) && !v.has(voxhap::volume::Channel::Intensity)) {
            voxhap::fuzz::finding("a loaded .vdb holds no channel grid");
        }
    } catch (const voxhap::Error& e) {
        voxhap::fuzz::checkRefusal(e, file.string());
    }
    return 0;
}
