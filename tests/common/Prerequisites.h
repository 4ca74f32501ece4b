// SPDX-License-Identifier: Apache-2.0
/// @file Prerequisites.h
/// @brief What a test needs beyond the build (a program, a display, a package's
/// files, the real data). Locally a missing prerequisite skips the test and says
/// why; CI sets VOXHAP_REQUIRE_ALL (.ci/run), which turns every such skip into a
/// failure naming what is missing, so that no test passes there without running.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>

namespace voxhap::test {

/// VOXHAP_REQUIRE_ALL is set (and not empty): nothing may be skipped.
inline bool allRequired()
{
    const char* v = std::getenv("VOXHAP_REQUIRE_ALL");
    return v != nullptr && *v != '\0';
}

} // namespace voxhap::test

/// In a test body or SetUp: unless @p present, skip (locally) or fail (under
/// VOXHAP_REQUIRE_ALL), naming @p what is missing.
#define VOXHAP_REQUIRE(present, what)                                                                                  \
    do {                                                                                                               \
        if (!(present)) {                                                                                              \
            if (::voxhap::test::allRequired())                                                                         \
                FAIL() << "missing prerequisite: " << what << " (VOXHAP_REQUIRE_ALL is set)";                          \
            GTEST_SKIP() << what << " (skipped locally; VOXHAP_REQUIRE_ALL fails it)";                                 \
        }                                                                                                              \
    } while (0)
