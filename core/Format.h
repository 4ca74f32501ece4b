// SPDX-License-Identifier: Apache-2.0
/// @file Format.h
/// @brief Numbers as people read them in reports and messages, one way.
#pragma once

#include <string>

namespace voxhap {

/// @brief @p value with exactly @p digits decimals ("12.35"), as std::fixed prints it,
/// except that a value that rounds to zero prints without a sign ("0.0", never "-0.0").
std::string fixed(double value, int digits = 1);

} // namespace voxhap
