// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/benchmarkTools/plot.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/image/text.hpp>
#include <cmath>
#include <cstdio>
#include <limits>

namespace asyncfem {

namespace {

std::string formatTick(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

struct Axis {
  double lo = 0.0, hi = 1.0;  // in axis units (log10 on log axes)
  bool log = false;
  double map(double value) const { return log ? std::log10(value) : value; }
};

Axis makeAxis(std::vector<double> values, bool logScale) {
  Axis axis;
  axis.log = logScale;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const double v : values) {
    if (!std::isfinite(v) || (logScale && v <= 0.0)) continue;
    const double m = logScale ? std::log10(v) : v;
    lo = std::min(lo, m);
    hi = std::max(hi, m);
  }
  if (!std::isfinite(lo)) {
    lo = 0.0;
    hi = 1.0;
  }
  if (logScale && hi - lo < 1.0) {
    lo = std::floor(lo);
    hi = std::max(std::ceil(hi), lo + 1.0);
  }
  if (hi == lo) {
    lo -= 0.5;
    hi += 0.5;
  }
  const double margin = 0.04 * (hi - lo);
  axis.lo = lo - margin;
  axis.hi = hi + margin;
  return axis;
}

/// Tick positions (axis units) and their labels.
std::vector<std::pair<double, std::string>> ticks(const Axis& axis) {
  std::vector<std::pair<double, std::string>> out;
  if (axis.log) {
    const int first = static_cast<int>(std::ceil(axis.lo)), last = static_cast<int>(std::floor(axis.hi));
    if (axis.hi - axis.lo >= 3.0) {
      const int stride = std::max(1, (last - first + 1) / 8);
      for (int k = first; k <= last; k += stride) out.emplace_back(k, "1E" + std::to_string(k));
      return out;
    }
    // Short log axes: 1-2-5 ticks inside every decade, labelled as plain numbers.
    for (int k = static_cast<int>(std::floor(axis.lo)); k <= static_cast<int>(std::ceil(axis.hi)); ++k) {
      for (const double factor : {1.0, 2.0, 5.0}) {
        const double position = k + std::log10(factor);
        if (position >= axis.lo && position <= axis.hi)
          out.emplace_back(position, formatTick(factor * std::pow(10.0, k)));
      }
    }
    return out;
  }
  const double span = axis.hi - axis.lo;
  const double raw = span / 6.0;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double step = magnitude;
  for (const double factor : {1.0, 2.0, 5.0, 10.0}) {
    step = factor * magnitude;
    if (span / step <= 7.0) break;
  }
  for (double t = std::ceil(axis.lo / step) * step; t <= axis.hi + 1e-9 * step; t += step) {
    out.emplace_back(t, formatTick(std::abs(t) < 1e-12 * step ? 0.0 : t));
  }
  return out;
}

void drawMarker(Image& image, int x, int y, Marker marker, Rgb8 color) {
  const int r = 4;
  switch (marker) {
    case Marker::none:
      return;
    case Marker::square:
      image.fillRectangle(x - r + 1, y - r + 1, x + r, y + r, color);
      return;
    case Marker::circle:
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx)
          if (dx * dx + dy * dy <= r * r) image.setPixel(x + dx, y + dy, color);
      return;
    case Marker::triangle:
      for (int dy = -r; dy <= r; ++dy) {
        const int half = (dy + r) / 2;
        for (int dx = -half; dx <= half; ++dx) image.setPixel(x + dx, y + dy, color);
      }
      return;
    case Marker::diamond:
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx)
          if (std::abs(dx) + std::abs(dy) <= r) image.setPixel(x + dx, y + dy, color);
      return;
    case Marker::cross:
      drawLine(image, x - r, y - r, x + r, y + r, color, 2);
      drawLine(image, x - r, y + r, x + r, y - r, color, 2);
      return;
    case Marker::plus:
      drawLine(image, x - r, y, x + r, y, color, 2);
      drawLine(image, x, y - r, x, y + r, color, 2);
      return;
  }
}

// Whether a point can be drawn: finite, and positive on a log axis.
bool drawable(const PlotSpec& spec, double x, double y) {
  return std::isfinite(x) && std::isfinite(y) && (!spec.logX || x > 0.0) && (!spec.logY || y > 0.0);
}

// The plot area in pixels and the axes mapped onto it.
struct PlotArea {
  int left = 0, right = 0, top = 0, bottom = 0;
  Axis ax, ay;
  // Pixel column of an axis-unit position (tick) and of a data value.
  int columnAt(double t) const {
    return left + static_cast<int>(std::lround((t - ax.lo) / (ax.hi - ax.lo) * (right - left)));
  }
  int rowAt(double t) const {
    return bottom - static_cast<int>(std::lround((t - ay.lo) / (ay.hi - ay.lo) * (bottom - top)));
  }
  int px(double v) const { return columnAt(ax.map(v)); }
  int py(double v) const { return rowAt(ay.map(v)); }
};

PlotArea plotArea(const PlotSpec& spec, int width, int height) {
  int legendWidth = 0;
  for (const PlotSeries& s : spec.series) legendWidth = std::max(legendWidth, textAdvance(s.label, 1));
  legendWidth = legendWidth > 0 ? legendWidth + 40 : 0;
  PlotArea area;
  area.left = 80;
  area.right = width - 20 - legendWidth;
  area.top = 50;
  area.bottom = height - 60;
  if (area.right - area.left < 50 || area.bottom - area.top < 50) {
    throw Error("renderPlot: image too small for the plot and its legend");
  }
  std::vector<double> xs, ys;
  for (const PlotSeries& s : spec.series) {
    for (std::size_t k = 0; k < s.x.size() && k < s.y.size(); ++k) {
      if (!drawable(spec, s.x[k], s.y[k])) continue;
      xs.push_back(s.x[k]);
      ys.push_back(s.y[k]);
    }
  }
  area.ax = makeAxis(xs, spec.logX);
  area.ay = makeAxis(ys, spec.logY);
  return area;
}

// Grid, tick labels, frame, title and axis labels.
void drawAxes(Image& image, const PlotSpec& spec, const PlotArea& a) {
  const Rgb8 black{0, 0, 0}, grid{225, 225, 225};
  for (const auto& [t, label] : ticks(a.ax)) {
    const int x = a.columnAt(t);
    drawLine(image, x, a.top, x, a.bottom, grid);
    drawLine(image, x, a.bottom, x, a.bottom + 5, black);
    drawText(image, x - textAdvance(label, 1) / 2, a.bottom + 10, label, 1, black);
  }
  for (const auto& [t, label] : ticks(a.ay)) {
    const int y = a.rowAt(t);
    drawLine(image, a.left, y, a.right, y, grid);
    drawLine(image, a.left - 5, y, a.left, y, black);
    drawText(image, a.left - 8 - textAdvance(label, 1), y - 3, label, 1, black);
  }
  drawLine(image, a.left, a.top, a.left, a.bottom, black);
  drawLine(image, a.left, a.bottom, a.right, a.bottom, black);
  drawLine(image, a.left, a.top, a.right, a.top, black);
  drawLine(image, a.right, a.top, a.right, a.bottom, black);
  drawText(image, (a.left + a.right - textAdvance(spec.title, 2)) / 2, 14, spec.title, 2, black);
  drawText(image, (a.left + a.right - textAdvance(spec.xLabel, 1)) / 2, a.bottom + 30, spec.xLabel, 1, black);
  drawText(image, 8, a.top - 16, spec.yLabel, 1, black);
}

// One series: markers, and lines between consecutive drawable points when connected.
void drawSeries(Image& image, const PlotSpec& spec, const PlotSeries& s, const PlotArea& a) {
  bool havePrevious = false;
  int previousX = 0, previousY = 0;
  for (std::size_t k = 0; k < s.x.size() && k < s.y.size(); ++k) {
    if (!drawable(spec, s.x[k], s.y[k])) {
      havePrevious = false;
      continue;
    }
    const int x = a.px(s.x[k]), y = a.py(s.y[k]);
    if (s.connect && havePrevious) drawLine(image, previousX, previousY, x, y, s.color, 2);
    drawMarker(image, x, y, s.marker, s.color);
    havePrevious = true;
    previousX = x;
    previousY = y;
  }
}

// The legend to the right of the plot area.
void drawLegend(Image& image, const PlotSpec& spec, const PlotArea& a) {
  int row = a.top;
  for (const PlotSeries& s : spec.series) {
    if (s.label.empty()) continue;
    const int x = a.right + 16;
    if (s.connect) drawLine(image, x, row + 3, x + 16, row + 3, s.color, 2);
    drawMarker(image, x + 8, row + 3, s.marker, s.color);
    drawText(image, x + 24, row, s.label, 1, Rgb8{0, 0, 0});
    row += 14;
  }
}

}  // namespace

Image renderPlot(const PlotSpec& spec, int width, int height) {
  Image image(width, height, Rgb8{255, 255, 255});
  const PlotArea area = plotArea(spec, width, height);
  drawAxes(image, spec, area);
  for (const PlotSeries& s : spec.series) drawSeries(image, spec, s, area);
  drawLegend(image, spec, area);
  return image;
}

Rgb8 paletteColor(int index) {
  static constexpr Rgb8 colors[] = {{31, 119, 180}, {214, 39, 40},   {44, 160, 44},  {255, 127, 14}, {148, 103, 189},
                                    {140, 86, 75},  {227, 119, 194}, {23, 190, 207}, {188, 189, 34}, {80, 80, 80}};
  return colors[static_cast<std::size_t>(index) % (sizeof colors / sizeof colors[0])];
}

Marker paletteMarker(int index) {
  static constexpr Marker markers[] = {Marker::circle,  Marker::square, Marker::triangle,
                                       Marker::diamond, Marker::cross,  Marker::plus};
  return markers[static_cast<std::size_t>(index) % 6];
}

}  // namespace asyncfem
