// SPDX-License-Identifier: Apache-2.0
/// @file BitmapFont.h
/// @brief A 5 × 7 pixel font for annotations (orientation letters, scale bar,
/// titles) drawn straight into an Image: no GL and no font files, so the
/// GL-free slice path and the 3D snapshots share the same lettering.
#pragma once

#include <array>
#include <cstdint>

namespace voxhap::render {

inline constexpr int kGlyphWidth = 5;   ///< [font pixels]
inline constexpr int kGlyphHeight = 7;  ///< [font pixels]
inline constexpr int kGlyphAdvance = 6; ///< glyph width plus one blank column

/// @brief The rows of a glyph, top first; bit 4 of a row is its leftmost pixel.
/// Printable ASCII without a glyph (and anything else) gets a hollow box.
std::array<std::uint8_t, kGlyphHeight> glyphRows(char c);

/// @brief True if @p c has its own glyph (not the box).
bool hasGlyph(char c);

} // namespace voxhap::render
