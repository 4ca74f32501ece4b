// SPDX-License-Identifier: Apache-2.0
/// @file SharedData.h
/// @brief The real data beside the project (../shared/data). Locally a missing
/// folder skips its tests with a message; CI sets VOXHAP_REQUIRE_SHARED_DATA
/// (.ci/run) so that a missing folder fails them instead of passing silently.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

namespace voxhap::test {

/// The abdominal CT series (TCIA, CC BY 4.0).
inline std::filesystem::path realCtDir()
{
    return std::filesystem::path(VOXHAP_SOURCE_DIR) / ".." / "shared" / "data" / "ct-abdomen-tcia" / "dicom";
}

inline bool sharedDataRequired() { return std::getenv("VOXHAP_REQUIRE_SHARED_DATA") != nullptr; }

} // namespace voxhap::test

/// In a test body: skip (locally) or fail (in CI) when @p dir is absent.
#define VOXHAP_REQUIRE_DIR(dir)                                                                                       \
    do {                                                                                                               \
        if (!std::filesystem::is_directory(dir)) {                                                                     \
            if (::voxhap::test::sharedDataRequired()) FAIL() << "shared data missing at " << (dir);                    \
            GTEST_SKIP() << "shared data not found at " << (dir) << " (skipped locally; CI requires it)";              \
        }                                                                                                              \
    } while (0)
