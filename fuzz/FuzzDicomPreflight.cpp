// SPDX-License-Identifier: Apache-2.0
/// @file FuzzDicomPreflight.cpp
/// @brief libFuzzer target: the DICOM structural walk, and the promise it
/// makes: a file it passes does not abort GDCM (Debian's GDCM asserts on
/// truncated elements, which is why the walk exists; DicomPreflight.h).

#include "FuzzInput.h"

#include "volume/DicomPreflight.h"

#include <gdcmImageReader.h>
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
    try {
        if (voxhap::volume::preflightDicom(file) == voxhap::volume::DicomKind::Dicom) {
            gdcm::ImageReader reader; // what loadDicom does with the pixels of a file that passed
            reader.SetFileName(file.string().c_str());
            reader.Read();
        }
    } catch (const voxhap::Error& e) {
        voxhap::fuzz::checkRefusal(e, file.string());
    }
    return 0;
}
