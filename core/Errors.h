// SPDX-License-Identifier: Apache-2.0
/// @file Errors.h
/// @brief The exceptions setup code throws (readers, parsers, validation).
///
/// Every message names the file and the offending field, so that the CLI can
/// print it as one line. Nothing on the servo path throws (architecture.md).
#pragma once

#include <stdexcept>
#include <string>

namespace voxhap {

/// @brief Base of voxhap's exceptions.
class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// @brief A file could not be read or written, or its content is malformed.
class IoError : public Error {
public:
    using Error::Error;
};

/// @brief A value is out of its allowed range or inconsistent with others.
class ValueError : public Error {
public:
    using Error::Error;
};

} // namespace voxhap
