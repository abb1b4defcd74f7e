// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/image/image.hpp>
#include <string>
#include <vector>

namespace asyncfem {

/// Glyph cell of the built-in bitmap font: 5 x 7 dots plus one column and one row of
/// spacing. Letters (drawn upper case), digits, space and . , : ; - _ + = / ( ) [ ] % # ' "
/// ! ? < > * ^ | are defined; other characters draw as a hollow box.
inline constexpr int glyphWidth = 5;
inline constexpr int glyphHeight = 7;

/// Width in pixels of text drawn at the given scale (each dot is scale x scale pixels):
/// from the first glyph's left edge to the last glyph's right edge, without the spacing
/// column after it (0 for empty text).
int textWidth(const std::string& text, int scale);
/// How far text moves the pen at the given scale: 6 dots per character, the spacing
/// column after the last glyph included (textWidth + scale for non-empty text). Layouts
/// that place text on a character grid (the benchmark plots) measure with this.
int textAdvance(const std::string& text, int scale);
/// Draws text with its top-left corner at (x, y), clipped to the image; glyph k starts at
/// x + 6 k scale.
void drawText(Image& image, int x, int y, const std::string& text, int scale, Rgb8 color);
void drawText(Image& image, int x, int y, const std::string& text, int scale, const Eigen::Vector3f& color);

/// Places images left to right, each under a coloured bar holding its label (centred,
/// in white), and returns the combined image. All images must have the same height and
/// labels must be empty or one per image (asyncfem::Error otherwise); without labels no
/// bar is drawn. barColors cycles through the given colours (a default palette if empty).
Image composeSideBySide(const std::vector<Image>& images, const std::vector<std::string>& labels, int barHeight,
                        const std::vector<Eigen::Vector3f>& barColors = {});

}  // namespace asyncfem
