// SPDX-License-Identifier: Apache-2.0
/// @file BuiltinTable.h
/// @brief The tissue table compiled into voxhap, under the short name tests use.
#pragma once

#include "volume/TissueTable.h"

namespace voxhap::test {

/// @brief The built-in tissue table (data/tissues.json).
inline const volume::TissueTable& table() { return volume::TissueTable::builtin(); }

} // namespace voxhap::test
