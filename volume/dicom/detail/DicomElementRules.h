// SPDX-License-Identifier: Apache-2.0
/// @file DicomElementRules.h
/// @brief Value representations of the image elements, and value-level checks
/// of the functional groups of enhanced (multi-frame)
/// DICOM objects, run before GDCM's ImageHelper reads their geometry.
///
/// Debian's GDCM 3.0 keeps its assertions: ImageHelper aborts the process on
/// an enhanced CT/MR file whose functional groups lack the plane orientation,
/// hold an empty or non-sequence Plane Position/Orientation/Pixel Measures
/// sequence, or give one frame another orientation than the shared one (found
/// by fuzz/FuzzDicomPreflight). These rules mirror each of those assertions
/// so that such files are refused with one line instead.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string_view>

namespace gdcm {
class DataSet;
}

namespace voxhap::volume {

/// @brief The value representations GDCM accepts for the image elements it
/// reads with gdcm::Attribute (geometry, pixel module, rescale): anything else
/// fails an assertion there. Empty for elements without a rule.
/// @return e.g. "DS", or "US|SS" when either is allowed
std::string_view expectedVr(std::uint16_t group, std::uint16_t element);

/// @brief True when @p ds carries functional groups, (5200,9229) or (5200,9230),
/// or is an ultrasound multi-frame object: GDCM reads their geometry on paths
/// that assert.
bool needsElementRules(const gdcm::DataSet& ds);

/// @brief Check the functional groups of @p ds (read from @p file).
/// @throw IoError "<file>: (gggg,eeee) Name: what is wrong"
void checkElementRules(const gdcm::DataSet& ds, const std::filesystem::path& file);

} // namespace voxhap::volume
