// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace asyncfem {

/// An 8-bit RGB colour.
struct Color {
  std::uint8_t r = 0, g = 0, b = 0;
};

/// A small RGB raster (row-major, top row first, 3 bytes per pixel) with the drawing
/// primitives the benchmark plots need. No dependency: writing it to a file is the
/// caller's business (the benchmark utility uses libpng).
class Image {
 public:
  Image(int width, int height, Color background = {255, 255, 255});
  int width() const { return width_; }
  int height() const { return height_; }
  /// width * height * 3 bytes, row-major from the top.
  const std::vector<std::uint8_t>& pixels() const { return pixels_; }
  Color at(int x, int y) const;
  /// Sets one pixel; coordinates outside the image are ignored (clipping).
  void set(int x, int y, Color color);
  void fillRect(int x0, int y0, int x1, int y1, Color color);
  /// Line from (x0, y0) to (x1, y1) (Bresenham), thickness in pixels (square pen).
  void line(int x0, int y0, int x1, int y1, Color color, int thickness = 1);
  /// Text in the built-in 5 x 7 bitmap font (upper-case letters, digits and common
  /// punctuation; lower case is drawn as upper case, unknown characters as '?'), top-left
  /// corner at (x, y), every font pixel drawn as scale x scale pixels. Character cell: 6
  /// by 8 font pixels.
  void text(int x, int y, const std::string& text, Color color, int scale = 1);
  /// Width in pixels of text at scale.
  static int textWidth(const std::string& text, int scale = 1);

 private:
  int width_, height_;
  std::vector<std::uint8_t> pixels_;
};

enum class Marker { none, circle, square, triangle, diamond, cross, plus };

/// One curve or point set of a plot.
struct PlotSeries {
  std::string label;         ///< legend entry ("" = not in the legend)
  std::vector<double> x, y;  ///< same length; non-finite points (and non-positive ones on log axes) are skipped
  Color color;
  Marker marker = Marker::circle;
  bool connect = false;  ///< draw lines between consecutive points
};

/// What to draw: axes (linear or base-10 logarithmic), tick labels, axis labels, title,
/// the series and a legend to the right of the plot area.
struct PlotSpec {
  std::string title, xLabel, yLabel;
  bool logX = false, logY = false;
  std::vector<PlotSeries> series;
};

/// Rasterizes a plot. Axis ranges cover every drawable point with a 4% margin (log axes
/// are widened to whole decades when they span less than one). Ticks: decades on log axes,
/// 1-2-5 steps on linear ones.
Image renderPlot(const PlotSpec& spec, int width = 1000, int height = 640);

/// A palette of distinguishable colours (cycled) and markers, for series index i.
Color paletteColor(int index);
Marker paletteMarker(int index);

}  // namespace asyncfem
