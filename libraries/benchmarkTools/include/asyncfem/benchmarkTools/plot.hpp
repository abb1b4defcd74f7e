// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/image/image.hpp>
#include <string>
#include <vector>

namespace asyncfem {

enum class Marker { none, circle, square, triangle, diamond, cross, plus };

/// One curve or point set of a plot.
struct PlotSeries {
  std::string label;         ///< legend entry ("" = not in the legend)
  std::vector<double> x, y;  ///< same length; non-finite points (and non-positive ones on log axes) are skipped
  Rgb8 color;
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

/// Rasterizes a plot on a white image (text in the bitmap font of asyncfem/image/text.hpp). Axis ranges cover every
/// drawable point with a 4% margin (log axes are widened to whole decades when they span less than one). Ticks: decades
/// on log axes, 1-2-5 steps on linear ones.
Image renderPlot(const PlotSpec& spec, int width = 1000, int height = 640);

/// A palette of distinguishable colours (cycled) and markers, for series index i.
Rgb8 paletteColor(int index);
Marker paletteMarker(int index);

}  // namespace asyncfem
