// SPDX-License-Identifier: Apache-2.0
/// @file InfoReport.h
/// @brief Text and JSON presentation of a VolumeInfo (`voxhap info`, `phantom`, `demo`).
#pragma once

#include "volume/VolumeInfo.h"

#include <nlohmann/json.hpp>

#include <ostream>
#include <string>

namespace voxhap::tools {

/// @brief The info as JSON; @p file names the volume's file.
nlohmann::json infoJson(const volume::VolumeInfo& info, const std::string& file);

/// @brief The info as an aligned, human-readable block of text.
void printInfo(std::ostream& os, const volume::VolumeInfo& info, const std::string& file);

} // namespace voxhap::tools
