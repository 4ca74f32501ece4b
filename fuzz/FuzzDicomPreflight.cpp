// SPDX-License-Identifier: Apache-2.0
/// @file FuzzDicomPreflight.cpp
/// @brief libFuzzer target: the DICOM loader end to end on one file — the
/// structural walk and element rules (DicomPreflight.h, DicomElementRules.h),
/// the header scan, the pixel-module checks, GDCM's decode and the sparse
/// conversion. Debian's GDCM asserts on malformed input, so whatever reaches
/// it must have been checked: a crash here is a rule missing before GDCM.

#include "FuzzInput.h"

#include "volume/dicom/DicomSeries.h"

#include <gdcmTrace.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    static voxhap::fuzz::ScratchFile scratch(".dcm");
    static const bool quiet = [] {
        gdcm::Trace::SetDebug(false);
        gdcm::Trace::SetWarning(false);
        gdcm::Trace::SetError(false);
        return true;
    }();
    (void)quiet;
    const auto& file = scratch.write(data, size);
    voxhap::volume::DicomOptions options;
    // Fuzzed headers declare any size: the loader must refuse before
    // allocating, well under libFuzzer's 2 GiB limit.
    options.memoryCapBytes = std::uint64_t(256) << 20;
    try {
        (void)voxhap::volume::loadDicom({file}, options);
    } catch (const voxhap::Error& e) {
        // Problems of the series as a whole (slice spacing, tilt) name its folder.
        voxhap::fuzz::checkRefusal(e, file.string(), file.parent_path().string());
    }
    return 0;
}
