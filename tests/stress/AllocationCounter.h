// SPDX-License-Identifier: Apache-2.0
/// @file AllocationCounter.h
/// @brief Every operator new of the stress program is counted, so that a test can
/// assert that a servo-path call allocates nothing (architecture.md "Threads").
#pragma once

namespace voxhap::test {
/// @brief Allocations so far in this program.
long allocations();
} // namespace voxhap::test
