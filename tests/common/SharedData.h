// SPDX-License-Identifier: Apache-2.0
/// @file SharedData.h
/// @brief The real data beside the project (../shared/data). Locally a missing
/// folder skips its tests with a message; VOXHAP_REQUIRE_SHARED_DATA, or
/// VOXHAP_REQUIRE_ALL which CI sets (.ci/run), makes a missing folder fail them
/// instead of passing silently.
#pragma once

#include "common/Prerequisites.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

namespace voxhap::test {

/// The abdominal CT series (TCIA, CC BY 4.0).
inline std::filesystem::path realCtDir()
{
    return std::filesystem::path(VOXHAP_SOURCE_DIR) / ".." / "shared" / "data" / "ct-abdomen-tcia" / "dicom";
}

/// The shared data folder beside the project.
inline std::filesystem::path sharedDataDir()
{
    return std::filesystem::path(VOXHAP_SOURCE_DIR) / ".." / "shared" / "data";
}

/// Siemens Trio 3 T head: a T1-weighted MPRAGE (sagittal, 256 × 256 × 176).
inline std::filesystem::path mprageDir() { return sharedDataDir() / "mr-head-trio" / "t1-mprage"; }

/// Siemens Trio 3 T head: a two-echo gradient-echo field map (magnitude), not T1.
inline std::filesystem::path fieldMapDir() { return sharedDataDir() / "mr-head-trio" / "gre-field-map"; }

/// Siemens Prisma 3 T: diffusion mosaics (13 volumes × 25 slices, one file each).
inline std::filesystem::path dwiMosaicDir() { return sharedDataDir() / "mr-dwi-prisma" / "dwi-mosaic"; }

/// Siemens Prisma 3 T: a T1-weighted sagittal 2D spoiled gradient echo (35 slices).
inline std::filesystem::path flash2dDir() { return sharedDataDir() / "mr-dwi-prisma" / "t1-fl2d-sag"; }

/// The reference converter's (dcm2niix) sidecars for the two Prisma series.
inline std::filesystem::path prismaReferenceDir() { return sharedDataDir() / "mr-dwi-prisma" / "reference"; }

/// The shared data must be present: VOXHAP_REQUIRE_SHARED_DATA (the data alone) or
/// VOXHAP_REQUIRE_ALL (every prerequisite) is set.
inline bool sharedDataRequired() { return std::getenv("VOXHAP_REQUIRE_SHARED_DATA") != nullptr || allRequired(); }

} // namespace voxhap::test

/// In a test body: skip (locally) or fail (in CI) when the shared data folder @p dir is absent.
#define VOXHAP_REQUIRE_DIR(dir)                                                                                        \
    do {                                                                                                               \
        if (!std::filesystem::is_directory(dir)) {                                                                     \
            if (::voxhap::test::sharedDataRequired()) FAIL() << "shared data missing at " << (dir);                    \
            GTEST_SKIP() << "shared data not found at " << (dir) << " (skipped locally; CI requires it)";              \
        }                                                                                                              \
    } while (0)
