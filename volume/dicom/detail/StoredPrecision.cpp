// SPDX-License-Identifier: Apache-2.0
/// @file StoredPrecision.cpp
/// @brief Units of decimal strings and the tolerances they imply.

#include "volume/dicom/detail/StoredPrecision.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace voxhap::volume {

double lastDigitUnit(const std::string& raw)
{
    std::size_t b = 0, e = raw.size();
    while (b < e && (std::isspace(static_cast<unsigned char>(raw[b])) || raw[b] == '\0')) ++b;
    while (e > b && (std::isspace(static_cast<unsigned char>(raw[e - 1])) || raw[e - 1] == '\0')) --e;
    const std::string text = raw.substr(b, e - b);
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v)) return 0.0;
    const std::size_t exp = text.find_first_of("eE");
    const std::string mantissa = text.substr(0, exp);
    const int exponent = exp == std::string::npos ? 0 : std::atoi(text.c_str() + exp + 1);
    const std::size_t dot = mantissa.find('.');
    // A whole number says nothing of the writer's precision: "0", "1" and
    // "-130" beside "-81.599998474121" are exact, not rounded to 1.
    if (dot == std::string::npos && exp == std::string::npos) return 0.0;
    const int decimals = dot == std::string::npos ? 0 : int(mantissa.size() - dot - 1);
    return std::pow(10.0, double(exponent - decimals));
}

double finestUnit(const std::string& text)
{
    double finest = 0;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, '\\')) {
        const double u = lastDigitUnit(item);
        if (u > 0 && (finest == 0 || u < finest)) finest = u;
    }
    return finest;
}

double positionToleranceMm(double unit) { return std::sqrt(3.0) * unit + kPositionFloorMm; }

double directionTolerance(double unit) { return std::max(std::sqrt(3.0) * unit, kDirectionFloor); }

} // namespace voxhap::volume
