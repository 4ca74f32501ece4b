// SPDX-License-Identifier: Apache-2.0
/// @file PrerequisiteProbe.cpp
/// @brief Tests whose prerequisites are missing on purpose, for CheckSwitch.sh:
/// a tool (VOXHAP_REQUIRE), a shared data folder (VOXHAP_REQUIRE_DIR), and a
/// test that fails when VOXHAP_PROBE_FAIL is set (a failure beside a skip).

#include "common/Prerequisites.h"
#include "common/SharedData.h"

#include <gtest/gtest.h>

#include <cstdlib>

namespace {

TEST(Probe, MissingTool) { VOXHAP_REQUIRE(false, "the probe's missing tool"); }

TEST(Probe, MissingSharedData) { VOXHAP_REQUIRE_DIR(voxhap::test::sharedDataDir() / "no-such-series-of-the-probe"); }

TEST(Probe, FailsOnRequest) { EXPECT_EQ(std::getenv("VOXHAP_PROBE_FAIL"), nullptr) << "failed on request"; }

} // namespace
