// SPDX-License-Identifier: Apache-2.0
/// @file ViewTypes.h
/// @brief The views, blend modes and CT window presets a render request names.
#pragma once

#include "core/Math.h"

#include <string>
#include <string_view>
#include <vector>

namespace voxhap::render {

/// @brief The four views of the planning layout.
enum class ViewKind {
    Axial,
    Sagittal,
    Coronal,
    ThreeD
};

/// @brief How the 3D view turns samples along a ray into a pixel (the four
/// display modes of the spine-biopsy simulator [K01], physics.md §1.1).
enum class BlendMode {
    Colour, ///< front-to-back compositing through the tissue colour transfer function
    Grey,   ///< front-to-back compositing, grey ramp over the window
    Mip,    ///< maximum intensity projection
    Sum,    ///< additive: the summed voxel projection (a radiograph-like image)
};

/// @brief A display window over image values: grey ramps from level − width/2
/// (black) to level + width/2 (white).
struct WindowLevel {
    double width = 400.0; ///< [HU] (or the T1 channel's unit)
    double level = 40.0;  ///< [HU]
};

/// @brief Common CT display presets (e.g. Radiopaedia "Windowing (CT)"):
/// bone W 1800 / L 400, soft tissue W 400 / L 40, lung W 1500 / L −600.
enum class WindowPreset {
    Bone,
    SoftTissue,
    Lung
};

WindowLevel windowLevel(WindowPreset p);

std::string_view viewName(ViewKind v); ///< "axial", "sagittal", "coronal", "3d"
/// @brief A pane's title: its name and, for a slice, where it cuts ("axial  z 12.5 mm").
std::string sliceTitle(ViewKind v, const Vec3d& point);
std::string_view blendModeName(BlendMode m); ///< "colour", "grey", "mip", "sum"

/// @brief Parse a comma-separated list of view names; duplicates collapse,
/// the result keeps the order axial, sagittal, coronal, 3d.
/// @throw ValueError naming the unknown view
std::vector<ViewKind> parseViews(std::string_view text);

/// @brief Parse "colour" ("color"), "grey" ("gray"), "mip" or "sum". @throw ValueError
BlendMode parseBlendMode(std::string_view text);

/// @brief Parse "bone", "soft" ("soft-tissue"), "lung", or "WIDTH,LEVEL" in HU.
/// @throw ValueError
WindowLevel parseWindow(std::string_view text);

/// @brief Whether @p text names a CT preset ("bone", "soft", "soft-tissue",
/// "lung"): values in HU, which mean nothing on MR. A caller showing MR refuses
/// such a name (WIDTH,LEVEL in the MR grid's own unit stays valid).
bool namesCtPreset(std::string_view text);

} // namespace voxhap::render
