// SPDX-License-Identifier: Apache-2.0
/// @file Format.cpp
#include "core/Format.h"

#include <iomanip>
#include <sstream>

namespace voxhap {

std::string fixed(double value, int digits)
{
    std::ostringstream os;
    os << std::fixed << std::setprecision(digits) << value;
    return os.str();
}

} // namespace voxhap
