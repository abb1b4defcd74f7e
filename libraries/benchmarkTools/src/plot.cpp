// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <array>
#include <asyncfem/benchmarkTools/plot.hpp>
#include <asyncfem/core/error.hpp>
#include <cmath>
#include <cstdio>
#include <limits>

namespace asyncfem {

namespace {

/// 5 x 7 glyph: seven rows, bit 4 = leftmost column.
using Glyph = std::array<std::uint8_t, 7>;

struct GlyphEntry {
  char character;
  Glyph rows;
};

// The font, drawn for this project: capitals, digits and the punctuation plots need.
constexpr GlyphEntry kFont[] = {
    {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},  {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}},  {'D', {0x1E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1E}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}},  {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}},  {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},  {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}},  {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}},  {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},  {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}},  {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}},  {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},  {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}},  {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x0A, 0x04, 0x04, 0x04, 0x04}},  {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}},  {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}},  {'3', {0x1E, 0x01, 0x01, 0x0E, 0x01, 0x01, 0x1E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}},  {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}},  {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}},  {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {' ', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}},  {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}},
    {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},  {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},  {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},  {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'/', {0x01, 0x01, 0x02, 0x04, 0x08, 0x10, 0x10}},  {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}},  {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
    {'<', {0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02}},  {'>', {0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08}},
    {'*', {0x00, 0x04, 0x15, 0x0E, 0x15, 0x04, 0x00}},  {'[', {0x0E, 0x08, 0x08, 0x08, 0x08, 0x08, 0x0E}},
    {']', {0x0E, 0x02, 0x02, 0x02, 0x02, 0x02, 0x0E}},  {'^', {0x04, 0x0A, 0x11, 0x00, 0x00, 0x00, 0x00}},
    {'|', {0x04, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},  {'#', {0x0A, 0x0A, 0x1F, 0x0A, 0x1F, 0x0A, 0x0A}},
    {'\'', {0x04, 0x04, 0x08, 0x00, 0x00, 0x00, 0x00}}, {'?', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x00, 0x04}},
    {'!', {0x04, 0x04, 0x04, 0x04, 0x04, 0x00, 0x04}},
};

const Glyph& glyphFor(char c) {
  if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
  for (const GlyphEntry& entry : kFont) {
    if (entry.character == c) return entry.rows;
  }
  for (const GlyphEntry& entry : kFont) {
    if (entry.character == '?') return entry.rows;
  }
  return kFont[0].rows;
}

constexpr int kCellWidth = 6, kCellHeight = 8;

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

void drawMarker(Image& image, int x, int y, Marker marker, Color color) {
  const int r = 4;
  switch (marker) {
    case Marker::none:
      return;
    case Marker::square:
      image.fillRect(x - r + 1, y - r + 1, x + r - 1, y + r - 1, color);
      return;
    case Marker::circle:
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx)
          if (dx * dx + dy * dy <= r * r) image.set(x + dx, y + dy, color);
      return;
    case Marker::triangle:
      for (int dy = -r; dy <= r; ++dy) {
        const int half = (dy + r) / 2;
        for (int dx = -half; dx <= half; ++dx) image.set(x + dx, y + dy, color);
      }
      return;
    case Marker::diamond:
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx)
          if (std::abs(dx) + std::abs(dy) <= r) image.set(x + dx, y + dy, color);
      return;
    case Marker::cross:
      image.line(x - r, y - r, x + r, y + r, color, 2);
      image.line(x - r, y + r, x + r, y - r, color, 2);
      return;
    case Marker::plus:
      image.line(x - r, y, x + r, y, color, 2);
      image.line(x, y - r, x, y + r, color, 2);
      return;
  }
}

}  // namespace

Image::Image(int width, int height, Color background) : width_(width), height_(height) {
  if (width <= 0 || height <= 0) throw Error("Image: width and height must be positive");
  pixels_.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3);
  for (std::size_t k = 0; k < pixels_.size(); k += 3) {
    pixels_[k] = background.r;
    pixels_[k + 1] = background.g;
    pixels_[k + 2] = background.b;
  }
}

Color Image::at(int x, int y) const {
  const std::size_t k =
      3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x));
  return {pixels_[k], pixels_[k + 1], pixels_[k + 2]};
}

void Image::set(int x, int y, Color color) {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return;
  const std::size_t k =
      3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x));
  pixels_[k] = color.r;
  pixels_[k + 1] = color.g;
  pixels_[k + 2] = color.b;
}

void Image::fillRect(int x0, int y0, int x1, int y1, Color color) {
  for (int y = std::min(y0, y1); y <= std::max(y0, y1); ++y)
    for (int x = std::min(x0, x1); x <= std::max(x0, x1); ++x) set(x, y, color);
}

void Image::line(int x0, int y0, int x1, int y1, Color color, int thickness) {
  const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0);
  const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
  int err = dx + dy;
  const int lo = -(thickness - 1) / 2, hi = thickness / 2;
  // Guard against absurd coordinates (points far off-screen): clip the step count.
  for (int guard = 0; guard < 100000; ++guard) {
    fillRect(x0 + lo, y0 + lo, x0 + hi, y0 + hi, color);
    if (x0 == x1 && y0 == y1) break;
    const int e2 = 2 * err;
    if (e2 >= dy) {
      err += dy;
      x0 += sx;
    }
    if (e2 <= dx) {
      err += dx;
      y0 += sy;
    }
  }
}

void Image::text(int x, int y, const std::string& text, Color color, int scale) {
  int cursor = x;
  for (const char c : text) {
    const Glyph& glyph = glyphFor(c);
    for (int row = 0; row < 7; ++row)
      for (int col = 0; col < 5; ++col)
        if (glyph[static_cast<std::size_t>(row)] & (0x10 >> col))
          fillRect(cursor + col * scale, y + row * scale, cursor + (col + 1) * scale - 1, y + (row + 1) * scale - 1,
                   color);
    cursor += kCellWidth * scale;
  }
}

int Image::textWidth(const std::string& text, int scale) { return static_cast<int>(text.size()) * kCellWidth * scale; }

Color paletteColor(int index) {
  static constexpr Color colors[] = {{31, 119, 180}, {214, 39, 40},   {44, 160, 44},  {255, 127, 14}, {148, 103, 189},
                                     {140, 86, 75},  {227, 119, 194}, {23, 190, 207}, {188, 189, 34}, {80, 80, 80}};
  return colors[static_cast<std::size_t>(index) % (sizeof colors / sizeof colors[0])];
}

Marker paletteMarker(int index) {
  static constexpr Marker markers[] = {Marker::circle,  Marker::square, Marker::triangle,
                                       Marker::diamond, Marker::cross,  Marker::plus};
  return markers[static_cast<std::size_t>(index) % 6];
}

Image renderPlot(const PlotSpec& spec, int width, int height) {
  Image image(width, height);
  const Color black{0, 0, 0}, grid{225, 225, 225};
  int legendWidth = 0;
  for (const PlotSeries& s : spec.series) legendWidth = std::max(legendWidth, Image::textWidth(s.label));
  legendWidth = legendWidth > 0 ? legendWidth + 40 : 0;
  const int left = 80, right = width - 20 - legendWidth, top = 50, bottom = height - 60;
  if (right - left < 50 || bottom - top < 50) throw Error("renderPlot: image too small for the plot and its legend");

  std::vector<double> xs, ys;
  for (const PlotSeries& s : spec.series) {
    for (std::size_t k = 0; k < s.x.size() && k < s.y.size(); ++k) {
      const bool ok = std::isfinite(s.x[k]) && std::isfinite(s.y[k]) && (!spec.logX || s.x[k] > 0.0) &&
                      (!spec.logY || s.y[k] > 0.0);
      if (!ok) continue;
      xs.push_back(s.x[k]);
      ys.push_back(s.y[k]);
    }
  }
  const Axis ax = makeAxis(xs, spec.logX), ay = makeAxis(ys, spec.logY);
  auto px = [&](double v) {
    return left + static_cast<int>(std::lround((ax.map(v) - ax.lo) / (ax.hi - ax.lo) * (right - left)));
  };
  auto py = [&](double v) {
    return bottom - static_cast<int>(std::lround((ay.map(v) - ay.lo) / (ay.hi - ay.lo) * (bottom - top)));
  };

  // Grid and tick labels.
  for (const auto& [t, label] : ticks(ax)) {
    const int x = left + static_cast<int>(std::lround((t - ax.lo) / (ax.hi - ax.lo) * (right - left)));
    image.line(x, top, x, bottom, grid);
    image.line(x, bottom, x, bottom + 5, black);
    image.text(x - Image::textWidth(label) / 2, bottom + 10, label, black);
  }
  for (const auto& [t, label] : ticks(ay)) {
    const int y = bottom - static_cast<int>(std::lround((t - ay.lo) / (ay.hi - ay.lo) * (bottom - top)));
    image.line(left, y, right, y, grid);
    image.line(left - 5, y, left, y, black);
    image.text(left - 8 - Image::textWidth(label), y - 3, label, black);
  }
  image.line(left, top, left, bottom, black);
  image.line(left, bottom, right, bottom, black);
  image.line(left, top, right, top, black);
  image.line(right, top, right, bottom, black);
  image.text((left + right - Image::textWidth(spec.title, 2)) / 2, 14, spec.title, black, 2);
  image.text((left + right - Image::textWidth(spec.xLabel)) / 2, bottom + 30, spec.xLabel, black);
  image.text(8, top - 16, spec.yLabel, black);

  // Series, clipped to the plot area by skipping points outside it.
  for (const PlotSeries& s : spec.series) {
    bool havePrevious = false;
    int previousX = 0, previousY = 0;
    for (std::size_t k = 0; k < s.x.size() && k < s.y.size(); ++k) {
      const bool ok = std::isfinite(s.x[k]) && std::isfinite(s.y[k]) && (!spec.logX || s.x[k] > 0.0) &&
                      (!spec.logY || s.y[k] > 0.0);
      if (!ok) {
        havePrevious = false;
        continue;
      }
      const int x = px(s.x[k]), y = py(s.y[k]);
      if (s.connect && havePrevious) image.line(previousX, previousY, x, y, s.color, 2);
      drawMarker(image, x, y, s.marker, s.color);
      havePrevious = true;
      previousX = x;
      previousY = y;
    }
  }

  // Legend to the right of the plot.
  int row = top;
  for (const PlotSeries& s : spec.series) {
    if (s.label.empty()) continue;
    const int x = right + 16;
    if (s.connect) image.line(x, row + 3, x + 16, row + 3, s.color, 2);
    drawMarker(image, x + 8, row + 3, s.marker, s.color);
    image.text(x + 24, row, s.label, black);
    row += 14;
  }
  return image;
}

}  // namespace asyncfem
