// A small SVG plotting module for the run reports: 2D figures with axes,
// round-numbered ticks, axis labels, a title, a legend and a colour bar.
//
// Series kinds: polylines (solid or dashed), scatter markers, polylines
// coloured per point by a scalar (viridis-like colour map, with a colour bar),
// and vertical bars (histograms). Figures may add horizontal and vertical
// reference lines (e.g. COLMAP's value, a threshold), a logarithmic x axis and
// an equal aspect ratio (trajectory views). A separate horizontal bar chart
// shows named values (e.g. per-stage timings).
//
// The axis range is the data range (series, bars and reference lines), widened
// by `margin_fraction` on each side: with no margin, a point at the data's
// minimum or maximum lies on the plot area's edge. The plot area is written as
// `<rect class="plot-area" x= y= width= height=>`.
//
// Output is deterministic: coordinates are written with 2 decimals, tick
// labels with the decimals their step needs. No scripts, no external files:
// the SVG can be inlined into an HTML page. The same layout is also drawn as
// a PNG (report/plot_canvas.h).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace viosfm {

struct Color {
  uint8_t r = 0;
  uint8_t g = 0;
  uint8_t b = 0;
  // "#rrggbb".
  std::string Hex() const;
  bool operator==(const Color& other) const = default;
};

// A viridis-like colour map: t = 0 dark purple, 0.5 teal, 1 yellow; t is
// clamped to [0, 1] (NaN maps to 0).
Color ColorMap(double t);

// A categorical palette (wraps around).
Color PaletteColor(int index);

enum class SeriesKind {
  kLine,         // polyline through (x[i], y[i])
  kScatter,      // a circle at each (x[i], y[i])
  kColoredLine,  // polyline whose segments take ColorMap of `values`
  kBars,         // vertical bars centred at x[i], from 0 to y[i], `bar_width` wide
};

struct Series {
  SeriesKind kind = SeriesKind::kLine;
  std::string label;  // legend text; empty: not in the legend
  std::vector<double> x;
  std::vector<double> y;
  // kColoredLine only: one scalar a point (e.g. position error, m).
  std::vector<double> values;
  Color color = {31, 119, 180};
  double line_width = 1.5;   // px
  bool dashed = false;       // kLine only
  double marker_radius = 3;  // px, kScatter only
  double bar_width = 1.0;    // data units, kBars only
};

struct ReferenceLine {
  double value = 0.0;  // y for a horizontal line, x for a vertical one
  std::string label;   // written next to the line; empty: none
  Color color = {90, 90, 90};
  bool dashed = true;
};

struct Figure {
  std::string title;
  std::string x_label;
  std::string y_label;
  double width = 640.0;   // px, whole figure
  double height = 400.0;  // px
  std::vector<Series> series;
  std::vector<ReferenceLine> horizontal_lines;
  std::vector<ReferenceLine> vertical_lines;
  // Logarithmic x axis (base 10); points with x <= 0 are left out.
  bool log_x = false;
  // One data unit spans as many pixels on both axes (the narrower range is
  // widened about its centre).
  bool equal_aspect = false;
  // Fraction of the data range added on each side of both axes (only above
  // for a y range that starts at 0 because of bars or y_from_zero). Default 0.
  double margin_fraction = 0.0;
  // Forces the y range to include 0 (bars always do).
  bool y_from_zero = false;
  // Colour bar for kColoredLine series: its label and range (default: the
  // values' min and max over all coloured series).
  std::string colorbar_label;
  std::optional<double> color_min;
  std::optional<double> color_max;
  // Legend position: inside the plot area's top-right (true) or top-left.
  bool legend_right = true;
};

// A horizontal bar chart: one bar a name, the value written after the bar.
struct BarChart {
  std::string title;
  std::string value_label;  // axis label of the values, e.g. "seconds"
  std::vector<std::string> names;
  std::vector<double> values;  // >= 0
  Color color = {31, 119, 180};
  double width = 640.0;      // px
  double bar_height = 18.0;  // px a bar; the figure's height follows
  int value_decimals = 2;    // decimals of the value text
};

// Round tick values ({1, 2, 5} x 10^k steps) within [min, max], about
// `target_count` of them (at least 2 when min < max; one when min == max).
std::vector<double> LinearTicks(double min, double max, int target_count = 6);
// Ticks of a log axis within [min, max] (min > 0): the powers of ten, plus
// 2 and 5 times them when the range spans fewer than 3 decades.
std::vector<double> LogTicks(double min, double max);
// A tick label: `value` with the decimals that `step` needs ("0.25", "100",
// "1e-05" for values below 1e-4 or from 1e6 on).
std::string FormatTick(double value, double step);

std::string RenderSvg(const Figure& figure);
std::string RenderSvg(const BarChart& chart);

// The same figure as a PNG file's bytes, drawn with OpenCV (anti-aliased
// lines, OpenCV's Hershey font), `scale` device pixels a figure pixel
// (default 2: sharp on high-density screens and in documents).
std::vector<uint8_t> RenderPng(const Figure& figure, double scale = 2.0);
std::vector<uint8_t> RenderPng(const BarChart& chart, double scale = 2.0);

// Write RenderSvg(...) / RenderPng(...) atomically to `path`.
void WriteSvg(const std::filesystem::path& path, const Figure& figure);
void WriteSvg(const std::filesystem::path& path, const BarChart& chart);
void WritePng(const std::filesystem::path& path, const Figure& figure, double scale = 2.0);
void WritePng(const std::filesystem::path& path, const BarChart& chart, double scale = 2.0);

// Escapes &, <, >, " and ' for XML text and attribute values.
std::string XmlEscape(const std::string& text);

}  // namespace viosfm
