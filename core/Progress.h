// SPDX-License-Identifier: Apache-2.0
/// @file Progress.h
/// @brief How a long job (a load, a segmentation) tells the caller how far it
/// got: one callback type for every library.
#pragma once

#include <functional>
#include <string_view>

namespace voxhap {

/// @brief Called with the fraction done (0 to 1; negative when the job cannot
/// tell, and the step's name says where it is) and the name of the step under
/// way (empty when the job has one step). May be empty; called from the job's
/// own thread, never from the servo path.
using Progress = std::function<void(double fraction, std::string_view step)>;

} // namespace voxhap
