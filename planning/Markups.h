// SPDX-License-Identifier: Apache-2.0
/// @file Markups.h
/// @brief 3D Slicer markups (.mrk.json) exchange: one Line markup per path, its
/// first control point the entry and its second the target, in LPS millimetres.
/// The writer fills the fields of Slicer's markups schema (v1.0.3: "@schema" and
/// "markups" at the top, "type" on each markup) and the ones Slicer writes itself,
/// so Slicer opens the file as it would its own; the reader is the one parser of
/// the project (PlanFile.cpp uses it too) and accepts LPS or RAS.
#pragma once

#include "core/Math.h"

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace voxhap::planning {

inline constexpr const char* kMarkupsSchema = "https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/"
                                              "Markups/Resources/Schema/markups-schema-v1.0.3.json#";

struct MarkupLine {
    std::string name;
    Vec3d entry{0, 0, 0};  ///< first control point [mm, LPS]
    Vec3d target{0, 0, 0}; ///< second control point [mm, LPS]
};

/// @brief The markups document text.
std::string markupsJson(const std::vector<MarkupLine>& lines);
/// @brief Write atomically. @throw IoError
void writeMarkups(const std::vector<MarkupLine>& lines, const std::filesystem::path& file);

/// @brief Every Line markup with two control points; other markup types are passed over.
/// @throw ValueError naming @p origin and the field (e.g. "markups[0].controlPoints[1].position")
std::vector<MarkupLine> parseMarkups(std::string_view json, const std::string& origin);
/// @throw IoError if unreadable, ValueError as parseMarkups
std::vector<MarkupLine> loadMarkups(const std::filesystem::path& file);

} // namespace voxhap::planning
