// SPDX-License-Identifier: Apache-2.0
/// @file ForcePlot.h
/// @brief The force–depth plot (PNG through gnuplot): model resistance and
/// rendered force, plunger force, layer bands and events.
#pragma once

#include "render/plots/ForceTrace.h"

#include <string>

namespace voxhap::render {

/// @return false with @p why set if gnuplot is missing or fails (the PNG then does not exist)
bool plotForceDepth(const ForceTrace& trace, const std::string& pngFile, std::string& why);

} // namespace voxhap::render
