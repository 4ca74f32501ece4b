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
    std::string s = os.str();
    // "-0.0" (a tiny negative, or -0.0 itself) reads as a different number: drop the sign.
    if (!s.empty() && s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
    return s;
}

} // namespace voxhap
