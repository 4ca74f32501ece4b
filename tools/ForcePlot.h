// SPDX-License-Identifier: Apache-2.0
/// @file ForcePlot.h
/// @brief The force–depth plot of an insertion (PNG through gnuplot): model and
/// rendered force, plunger force, layer bands and events.
#pragma once

#include "haptic/Insertion.h"

#include <string>
#include <vector>

namespace voxhap::tools {

/// @return false with @p why set if gnuplot is missing or fails
bool plotForceDepth(const haptic::InsertionResult& r, const std::vector<haptic::Layer>& layers, const std::string& title,
                    const std::string& pngFile, std::string& why);

} // namespace voxhap::tools
