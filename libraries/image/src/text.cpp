// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/image/text.hpp>
#include <cctype>
#include <string>

namespace asyncfem {

namespace {

/// One glyph: its character and seven rows of five dots, bit 4 the leftmost dot. The
/// comment after each entry shows the rows ('#' = dot) from top to bottom.
struct Glyph {
  char character;
  std::array<unsigned char, glyphHeight> rows;
};

constexpr Glyph glyphs[] = {
    {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},   // .###. #...# #...# ##### #...# #...# #...#
    {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},   // ####. #...# #...# ####. #...# #...# ####.
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}},   // .###. #...# #.... #.... #.... #...# .###.
    {'D', {0x1E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1E}},   // ####. #...# #...# #...# #...# #...# ####.
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}},   // ##### #.... #.... ####. #.... #.... #####
    {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},   // ##### #.... #.... ####. #.... #.... #....
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0E}},   // .###. #...# #.... #.### #...# #...# .###.
    {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},   // #...# #...# #...# ##### #...# #...# #...#
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},   // .###. ..#.. ..#.. ..#.. ..#.. ..#.. .###.
    {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},   // ..### ...#. ...#. ...#. ...#. #..#. .##..
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}},   // #...# #..#. #.#.. ##... #.#.. #..#. #...#
    {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},   // #.... #.... #.... #.... #.... #.... #####
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}},   // #...# ##.## #.#.# #.#.# #...# #...# #...#
    {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},   // #...# #...# ##..# #.#.# #..## #...# #...#
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},   // .###. #...# #...# #...# #...# #...# .###.
    {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},   // ####. #...# #...# ####. #.... #.... #....
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}},   // .###. #...# #...# #...# #.#.# #..#. .##.#
    {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},   // ####. #...# #...# ####. #.#.. #..#. #...#
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}},   // .#### #.... #.... .###. ....# ....# ####.
    {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},   // ##### ..#.. ..#.. ..#.. ..#.. ..#.. ..#..
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},   // #...# #...# #...# #...# #...# #...# .###.
    {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},   // #...# #...# #...# #...# #...# .#.#. ..#..
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}},   // #...# #...# #...# #.#.# #.#.# #.#.# .#.#.
    {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},   // #...# #...# .#.#. ..#.. .#.#. #...# #...#
    {'Y', {0x11, 0x11, 0x0A, 0x04, 0x04, 0x04, 0x04}},   // #...# #...# .#.#. ..#.. ..#.. ..#.. ..#..
    {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},   // ##### ....# ...#. ..#.. .#... #.... #####
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}},   // .###. #...# #..## #.#.# ##..# #...# .###.
    {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},   // ..#.. .##.. ..#.. ..#.. ..#.. ..#.. .###.
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}},   // .###. #...# ....# ...#. ..#.. .#... #####
    {'3', {0x1E, 0x01, 0x01, 0x0E, 0x01, 0x01, 0x1E}},   // ####. ....# ....# .###. ....# ....# ####.
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}},   // ...#. ..##. .#.#. #..#. ##### ...#. ...#.
    {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},   // ##### #.... ####. ....# ....# #...# .###.
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}},   // ..##. .#... #.... ####. #...# #...# .###.
    {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},   // ##### ....# ...#. ..#.. .#... .#... .#...
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}},   // .###. #...# #...# .###. #...# #...# .###.
    {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},   // .###. #...# #...# .#### ....# ...#. .##..
    {' ', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}},   // ..... ..... ..... ..... ..... ..... .....
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}},   // ..... ..... ..... ..... ..... .##.. .##..
    {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},   // ..... ..... ..... ..... .##.. ..#.. .#...
    {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},   // ..... .##.. .##.. ..... .##.. .##.. .....
    {';', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x04, 0x08}},   // ..... .##.. .##.. ..... .##.. ..#.. .#...
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},   // ..... ..... ..... ##### ..... ..... .....
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}},   // ..... ..... ..... ..... ..... ..... #####
    {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},   // ..... ..#.. ..#.. ##### ..#.. ..#.. .....
    {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},   // ..... ..... ##### ..... ##### ..... .....
    {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},   // ..... ....# ...#. ..#.. .#... #.... .....
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},   // ...#. ..#.. .#... .#... .#... ..#.. ...#.
    {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},   // .#... ..#.. ...#. ...#. ...#. ..#.. .#...
    {'[', {0x0E, 0x08, 0x08, 0x08, 0x08, 0x08, 0x0E}},   // .###. .#... .#... .#... .#... .#... .###.
    {']', {0x0E, 0x02, 0x02, 0x02, 0x02, 0x02, 0x0E}},   // .###. ...#. ...#. ...#. ...#. ...#. .###.
    {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},   // ##... ##..# ...#. ..#.. .#... #..## ...##
    {'#', {0x0A, 0x0A, 0x1F, 0x0A, 0x1F, 0x0A, 0x0A}},   // .#.#. .#.#. ##### .#.#. ##### .#.#. .#.#.
    {'\'', {0x04, 0x04, 0x08, 0x00, 0x00, 0x00, 0x00}},  // ..#.. ..#.. .#... ..... ..... ..... .....
    {'"', {0x0A, 0x0A, 0x0A, 0x00, 0x00, 0x00, 0x00}},   // .#.#. .#.#. .#.#. ..... ..... ..... .....
    {'!', {0x04, 0x04, 0x04, 0x04, 0x04, 0x00, 0x04}},   // ..#.. ..#.. ..#.. ..#.. ..#.. ..... ..#..
    {'?', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x00, 0x04}},   // .###. #...# ....# ...#. ..#.. ..... ..#..
    {'<', {0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02}},   // ...#. ..#.. .#... #.... .#... ..#.. ...#.
    {'>', {0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08}},   // .#... ..#.. ...#. ....# ...#. ..#.. .#...
    {'*', {0x00, 0x04, 0x15, 0x0E, 0x15, 0x04, 0x00}},   // ..... ..#.. #.#.# .###. #.#.# ..#.. .....
    {'^', {0x04, 0x0A, 0x11, 0x00, 0x00, 0x00, 0x00}},   // ..#.. .#.#. #...# ..... ..... ..... .....
    {'|', {0x04, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},   // ..#.. ..#.. ..#.. ..#.. ..#.. ..#.. ..#..
};

/// Drawn for characters without a glyph: a hollow box.
constexpr std::array<unsigned char, glyphHeight> missingGlyph = {0x1F, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1F};

const std::array<unsigned char, glyphHeight>& glyphRows(char c) {
  const char upper = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  for (const Glyph& glyph : glyphs) {
    if (glyph.character == upper) {
      return glyph.rows;
    }
  }
  return missingGlyph;
}

}  // namespace

int textWidth(const std::string& text, int scale) {
  if (text.empty()) {
    return 0;
  }
  return ((static_cast<int>(text.size()) * (glyphWidth + 1)) - 1) * scale;
}

int textAdvance(const std::string& text, int scale) { return static_cast<int>(text.size()) * (glyphWidth + 1) * scale; }

void drawText(Image& image, int x, int y, const std::string& text, int scale, const Eigen::Vector3f& color) {
  drawText(image, x, y, text, scale, toRgb8(color));
}

void drawText(Image& image, int x, int y, const std::string& text, int scale, Rgb8 color) {
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto& rows = glyphRows(text[i]);
    const int left = x + (static_cast<int>(i) * (glyphWidth + 1) * scale);
    for (int row = 0; row < glyphHeight; ++row) {
      for (int column = 0; column < glyphWidth; ++column) {
        if ((rows[static_cast<std::size_t>(row)] & (1U << (glyphWidth - 1 - column))) != 0) {
          image.fillRectangle(left + (column * scale), y + (row * scale), left + ((column + 1) * scale),
                              y + ((row + 1) * scale), color);
        }
      }
    }
  }
}

namespace {

// Sum of the images' widths; throws Error unless they all have the first one's height.
int sideBySideWidth(const std::vector<Image>& images) {
  int width = 0;
  for (const Image& image : images) {
    if (image.height != images.front().height) {
      throw Error("composeSideBySide: images of different heights (" + std::to_string(image.height) + " and " +
                  std::to_string(images.front().height) + ")");
    }
    width += image.width;
  }
  return width;
}

// Fills rows [0, bar) of columns [x, x + width) of out with color and centres label on it
// in white, at the largest scale whose glyphs fill at most 70% of the bar and whose text
// fits.
void drawLabelBar(Image& out, int x, int width, int bar, const std::string& label, const Eigen::Vector3f& color) {
  out.fillRectangle(x, 0, x + width, bar, color);
  int scale = std::max(1, (bar * 7) / (10 * glyphHeight));
  while (scale > 1 && textWidth(label, scale) > width - 4) {
    --scale;
  }
  const int textX = x + ((width - textWidth(label, scale)) / 2);
  const int textY = (bar - (glyphHeight * scale)) / 2;
  drawText(out, std::max(x, textX), textY, label, scale, Eigen::Vector3f::Ones());
}

}  // namespace

Image composeSideBySide(const std::vector<Image>& images, const std::vector<std::string>& labels, int barHeight,
                        const std::vector<Eigen::Vector3f>& barColors) {
  if (images.empty()) {
    throw Error("composeSideBySide: no images");
  }
  if (!labels.empty() && labels.size() != images.size()) {
    throw Error("composeSideBySide: " + std::to_string(labels.size()) + " labels for " + std::to_string(images.size()) +
                " images");
  }
  const int width = sideBySideWidth(images);
  const int bar = labels.empty() ? 0 : std::max(barHeight, 0);
  const std::vector<Eigen::Vector3f> palette =
      barColors.empty()
          ? std::vector<Eigen::Vector3f>{{0.85F, 0.38F, 0.12F}, {0.20F, 0.42F, 0.72F}, {0.25F, 0.60F, 0.30F}}
          : barColors;
  Image out(width, images.front().height + bar, Eigen::Vector3f::Ones());
  int x = 0;
  for (std::size_t i = 0; i < images.size(); ++i) {
    const Image& image = images[i];
    if (bar > 0) drawLabelBar(out, x, image.width, bar, labels[i], palette[i % palette.size()]);
    out.paste(image, x, bar);
    x += image.width;
  }
  return out;
}

}  // namespace asyncfem
