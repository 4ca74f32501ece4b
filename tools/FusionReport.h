// SPDX-License-Identifier: Apache-2.0
/// @file FusionReport.h
/// @brief A fused volume's registration record as `voxhap fuse` and `voxhap info`
/// print it (JSON: volume::toJson).
#pragma once

#include "volume/FusionRecord.h"

#include <ostream>
#include <string>

namespace voxhap::tools {

/// @brief The registration summary, one fact per line, each prefixed by @p indent.
void printFusionRecord(std::ostream& os, const volume::FusionRecord& r, const std::string& indent = "");

} // namespace voxhap::tools
