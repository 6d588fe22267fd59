#include "viosfm/report/svg_plot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "viosfm/report/plot_canvas.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"

namespace viosfm {
namespace {

// Pixel sizes of the figure furniture.
constexpr double kLeftMargin = 68.0;     // y tick labels and y label
constexpr double kRightMargin = 16.0;    // without a colour bar
constexpr double kColorBarSpace = 86.0;  // colour bar, its ticks and label
constexpr double kTopMarginTitle = 34.0;
constexpr double kTopMarginPlain = 14.0;
constexpr double kBottomMargin = 50.0;  // x tick labels and x label
constexpr double kCharWidth = 6.6;      // approximate width of a 12 px glyph
constexpr int kColorBarSteps = 48;
constexpr double kMinPointSpacing = 0.5;  // px between written polyline points

// A coordinate in pixels, 2 decimals, never "-0.00".
std::string Px(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.2f", value);
  std::string text = buffer;
  if (text == "-0.00") text = "0.00";
  return text;
}

struct Range {
  double min = std::numeric_limits<double>::infinity();
  double max = -std::numeric_limits<double>::infinity();
  void Add(double v) {
    if (!std::isfinite(v)) return;
    min = std::min(min, v);
    max = std::max(max, v);
  }
  bool Empty() const { return !(min <= max); }
  double Span() const { return max - min; }
};

// Gives an empty or degenerate range a width, then adds the margin.
void Finish(Range* range, double margin_fraction) {
  if (range->Empty()) {
    range->min = 0.0;
    range->max = 1.0;
  } else if (range->Span() == 0.0) {
    const double half = range->min == 0.0 ? 0.5 : 0.1 * std::abs(range->min);
    range->min -= half;
    range->max += half;
  }
  const double margin = margin_fraction * range->Span();
  range->min -= margin;
  range->max += margin;
}

// Maps data coordinates to pixels.
struct Axes {
  double left = 0, top = 0, width = 0, height = 0;  // plot area, px
  Range x;                                          // in axis units (log10 of x for a log axis)
  Range y;
  bool log_x = false;

  double AxisX(double x) const { return log_x ? std::log10(x) : x; }
  double X(double x) const { return left + (AxisX(x) - this->x.min) / this->x.Span() * width; }
  double Y(double y) const { return top + height - (y - this->y.min) / this->y.Span() * height; }
};

const Color kTickColor = {0x33, 0x33, 0x33};
const Color kGridColor = {0xe6, 0xe6, 0xe6};
const Color kWhite = {0xff, 0xff, 0xff};

const char* AnchorName(TextAnchor anchor) {
  switch (anchor) {
    case TextAnchor::kStart: return "start";
    case TextAnchor::kMiddle: return "middle";
    case TextAnchor::kEnd: return "end";
  }
  return "start";
}

PlotTextStyle Anchored(TextAnchor anchor) {
  PlotTextStyle style;
  style.anchor = anchor;
  return style;
}

PlotTextStyle TitleStyle() {
  PlotTextStyle style = Anchored(TextAnchor::kMiddle);
  style.size = 14.0;
  style.bold = true;
  return style;
}

PlotTextStyle VerticalStyle() {
  PlotTextStyle style = Anchored(TextAnchor::kMiddle);
  style.vertical = true;
  return style;
}

PlotRectStyle Filled(const Color& color) {
  PlotRectStyle style;
  style.fill = color;
  return style;
}

PlotRectStyle Framed(const std::string& css_class) {
  PlotRectStyle style;
  style.outline = PlotStroke{kTickColor, 1.0, false};
  style.css_class = css_class;
  return style;
}

class SvgWriter : public PlotCanvas {
 public:
  SvgWriter(double width, double height) {
    out_ << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << Px(width) << "\" height=\""
         << Px(height) << "\" viewBox=\"0 0 " << Px(width) << ' ' << Px(height)
         << "\" font-family=\"sans-serif\" font-size=\"12\">\n";
    out_ << "<rect x=\"0.00\" y=\"0.00\" width=\"" << Px(width) << "\" height=\"" << Px(height)
         << "\" fill=\"#ffffff\"/>\n";
  }
  void Line(double x1, double y1, double x2, double y2, const PlotStroke& stroke) override {
    out_ << "<line x1=\"" << Px(x1) << "\" y1=\"" << Px(y1) << "\" x2=\"" << Px(x2) << "\" y2=\""
         << Px(y2) << "\" stroke=\"" << stroke.color.Hex() << "\" stroke-width=\""
         << Px(stroke.width) << '"';
    if (stroke.dashed) out_ << " stroke-dasharray=\"6 4\"";
    out_ << "/>\n";
  }
  void Text(double x, double y, const std::string& text, const PlotTextStyle& style) override {
    out_ << "<text x=\"" << Px(x) << "\" y=\"" << Px(y) << "\" text-anchor=\""
         << AnchorName(style.anchor) << '"';
    if (style.size != 12.0) out_ << " font-size=\"" << FormatNumber(style.size) << '"';
    if (style.bold) out_ << " font-weight=\"bold\"";
    if (style.vertical) out_ << " transform=\"rotate(-90 " << Px(x) << ' ' << Px(y) << ")\"";
    if (style.color) out_ << " fill=\"" << style.color->Hex() << '"';
    out_ << '>' << XmlEscape(text) << "</text>\n";
  }
  void Rect(double x, double y, double width, double height, const PlotRectStyle& style) override {
    out_ << "<rect x=\"" << Px(x) << "\" y=\"" << Px(y) << "\" width=\"" << Px(width)
         << "\" height=\"" << Px(height) << "\" fill=\""
         << (style.fill ? style.fill->Hex() : std::string("none")) << '"';
    if (!style.css_class.empty()) out_ << " class=\"" << style.css_class << '"';
    if (style.fill_opacity < 1.0) out_ << " fill-opacity=\"" << Px(style.fill_opacity) << '"';
    if (style.outline) {
      out_ << " stroke=\"" << style.outline->color.Hex() << "\" stroke-width=\""
           << Px(style.outline->width) << '"';
    }
    out_ << "/>\n";
  }
  void Circle(double cx, double cy, double radius, const Color& fill) override {
    out_ << "<circle cx=\"" << Px(cx) << "\" cy=\"" << Px(cy) << "\" r=\"" << Px(radius)
         << "\" fill=\"" << fill.Hex() << "\"/>\n";
  }
  void Polyline(const std::vector<std::pair<double, double>>& points,
                const PlotStroke& stroke) override {
    if (points.size() < 2) return;
    out_ << "<polyline fill=\"none\" stroke=\"" << stroke.color.Hex() << "\" stroke-width=\""
         << Px(stroke.width) << "\" stroke-linejoin=\"round\" stroke-linecap=\"round\"";
    if (stroke.dashed) out_ << " stroke-dasharray=\"6 4\"";
    out_ << " points=\"";
    // Points closer than kMinPointSpacing to the last written one are left
    // out (the last point is always written): a 200 Hz ground truth stays small.
    std::pair<double, double> last = points.front();
    out_ << Px(last.first) << ',' << Px(last.second);
    for (size_t i = 1; i < points.size(); ++i) {
      const double dx = points[i].first - last.first;
      const double dy = points[i].second - last.second;
      if (i + 1 < points.size() && dx * dx + dy * dy < kMinPointSpacing * kMinPointSpacing) {
        continue;
      }
      last = points[i];
      out_ << ' ' << Px(last.first) << ',' << Px(last.second);
    }
    out_ << "\"/>\n";
  }
  std::string Finish() {
    out_ << "</svg>\n";
    return out_.str();
  }

 private:
  static std::string FormatNumber(double value) {
    char buffer[32];
    std::snprintf(buffer, sizeof(buffer), "%g", value);
    return buffer;
  }
  std::ostringstream out_;
};

bool Usable(const Figure& figure, double x, double y) {
  return std::isfinite(x) && std::isfinite(y) && (!figure.log_x || x > 0.0);
}

std::pair<double, double> ColorRange(const Figure& figure) {
  Range range;
  for (const Series& s : figure.series) {
    if (s.kind != SeriesKind::kColoredLine) continue;
    for (double v : s.values) range.Add(v);
  }
  double min = figure.color_min.value_or(range.Empty() ? 0.0 : range.min);
  double max = figure.color_max.value_or(range.Empty() ? 1.0 : range.max);
  if (!(max > min)) max = min + 1.0;
  return {min, max};
}

bool HasColoredSeries(const Figure& figure) {
  return std::any_of(figure.series.begin(), figure.series.end(),
                     [](const Series& s) { return s.kind == SeriesKind::kColoredLine; });
}

Axes ComputeAxes(const Figure& figure) {
  Axes axes;
  axes.log_x = figure.log_x;
  const bool color_bar = HasColoredSeries(figure);
  axes.left = kLeftMargin;
  axes.top = figure.title.empty() ? kTopMarginPlain : kTopMarginTitle;
  axes.width = std::max(
      10.0, figure.width - kLeftMargin - kRightMargin - (color_bar ? kColorBarSpace : 0.0));
  axes.height = std::max(10.0, figure.height - axes.top - kBottomMargin);

  for (const Series& s : figure.series) {
    const size_t n = std::min(s.x.size(), s.y.size());
    for (size_t i = 0; i < n; ++i) {
      if (!Usable(figure, s.x[i], s.y[i])) continue;
      if (s.kind == SeriesKind::kBars) {
        const double half = 0.5 * s.bar_width;
        if (!figure.log_x || s.x[i] - half > 0.0) axes.x.Add(axes.AxisX(s.x[i] - half));
        axes.x.Add(axes.AxisX(s.x[i] + half));
        axes.y.Add(0.0);
      } else {
        axes.x.Add(axes.AxisX(s.x[i]));
      }
      axes.y.Add(s.y[i]);
    }
  }
  for (const ReferenceLine& line : figure.horizontal_lines) axes.y.Add(line.value);
  for (const ReferenceLine& line : figure.vertical_lines) {
    if (!figure.log_x || line.value > 0.0) axes.x.Add(axes.AxisX(line.value));
  }
  if (figure.y_from_zero) axes.y.Add(0.0);
  // Bars (and y_from_zero figures) with no negative value keep 0 on the axis:
  // the margin is added above only.
  const bool has_bars = std::any_of(figure.series.begin(), figure.series.end(),
                                    [](const Series& s) { return s.kind == SeriesKind::kBars; });
  const bool anchor_zero = (has_bars || figure.y_from_zero) && axes.y.min == 0.0;
  Finish(&axes.x, figure.margin_fraction);
  Finish(&axes.y, figure.margin_fraction);
  if (anchor_zero) axes.y.min = 0.0;

  if (figure.equal_aspect && !figure.log_x) {
    // Pixels a data unit: the smaller of the two, so that all data fits.
    const double sx = axes.width / axes.x.Span();
    const double sy = axes.height / axes.y.Span();
    const double s = std::min(sx, sy);
    const double half_x = 0.5 * axes.width / s;
    const double half_y = 0.5 * axes.height / s;
    const double cx = 0.5 * (axes.x.min + axes.x.max);
    const double cy = 0.5 * (axes.y.min + axes.y.max);
    axes.x.min = cx - half_x;
    axes.x.max = cx + half_x;
    axes.y.min = cy - half_y;
    axes.y.max = cy + half_y;
  }
  return axes;
}

double TickStep(const std::vector<double>& ticks) {
  return ticks.size() >= 2 ? ticks[1] - ticks[0] : (ticks.empty() ? 1.0 : std::abs(ticks[0]));
}

void DrawAxes(const Figure& figure, const Axes& axes, PlotCanvas* svg) {
  const double right = axes.left + axes.width;
  const double bottom = axes.top + axes.height;
  // x ticks and grid.
  const int x_target = std::max(2, static_cast<int>(axes.width / 90.0));
  if (figure.log_x) {
    const std::vector<double> ticks =
        LogTicks(std::pow(10.0, axes.x.min), std::pow(10.0, axes.x.max));
    for (double t : ticks) {
      const double px = axes.X(t);
      svg->Line(px, axes.top, px, bottom, {kGridColor, 1.0});
      svg->Line(px, bottom, px, bottom + 5, {kTickColor, 1.0});
      svg->Text(px, bottom + 18, FormatTick(t, t), Anchored(TextAnchor::kMiddle));
    }
  } else {
    const std::vector<double> ticks = LinearTicks(axes.x.min, axes.x.max, x_target);
    const double step = TickStep(ticks);
    for (double t : ticks) {
      const double px = axes.X(t);
      svg->Line(px, axes.top, px, bottom, {kGridColor, 1.0});
      svg->Line(px, bottom, px, bottom + 5, {kTickColor, 1.0});
      svg->Text(px, bottom + 18, FormatTick(t, step), Anchored(TextAnchor::kMiddle));
    }
  }
  // y ticks and grid.
  const int y_target = std::max(2, static_cast<int>(axes.height / 55.0));
  const std::vector<double> y_ticks = LinearTicks(axes.y.min, axes.y.max, y_target);
  const double y_step = TickStep(y_ticks);
  for (double t : y_ticks) {
    const double py = axes.Y(t);
    svg->Line(axes.left, py, right, py, {kGridColor, 1.0});
    svg->Line(axes.left - 5, py, axes.left, py, {kTickColor, 1.0});
    svg->Text(axes.left - 8, py + 4, FormatTick(t, y_step), Anchored(TextAnchor::kEnd));
  }
  // Frame of the plot area (drawn after the grid).
  svg->Rect(axes.left, axes.top, axes.width, axes.height, Framed("plot-area"));
  if (!figure.title.empty()) {
    svg->Text(axes.left + 0.5 * axes.width, 22, figure.title, TitleStyle());
  }
  if (!figure.x_label.empty()) {
    svg->Text(axes.left + 0.5 * axes.width, bottom + 38, figure.x_label,
              Anchored(TextAnchor::kMiddle));
  }
  if (!figure.y_label.empty()) {
    const double x = 16.0;
    const double y = axes.top + 0.5 * axes.height;
    svg->Text(x, y, figure.y_label, VerticalStyle());
  }
}

void DrawSeries(const Figure& figure, const Axes& axes, PlotCanvas* svg) {
  const auto [color_min, color_max] = ColorRange(figure);
  for (const Series& s : figure.series) {
    const size_t n = std::min(s.x.size(), s.y.size());
    switch (s.kind) {
      case SeriesKind::kLine: {
        // A gap (unusable point) splits the polyline.
        std::vector<std::pair<double, double>> points;
        for (size_t i = 0; i <= n; ++i) {
          if (i < n && Usable(figure, s.x[i], s.y[i])) {
            points.emplace_back(axes.X(s.x[i]), axes.Y(s.y[i]));
            continue;
          }
          svg->Polyline(points, {s.color, s.line_width, s.dashed});
          points.clear();
        }
        break;
      }
      case SeriesKind::kScatter:
        for (size_t i = 0; i < n; ++i) {
          if (!Usable(figure, s.x[i], s.y[i])) continue;
          svg->Circle(axes.X(s.x[i]), axes.Y(s.y[i]), s.marker_radius, s.color);
        }
        break;
      case SeriesKind::kColoredLine: {
        // Consecutive segments of one colour are merged into one polyline.
        VIOSFM_CHECK_EQ(s.values.size(), n) << "kColoredLine needs one value a point";
        std::vector<std::pair<double, double>> points;
        std::optional<Color> run_color;
        for (size_t i = 0; i + 1 < n; ++i) {
          if (!Usable(figure, s.x[i], s.y[i]) || !Usable(figure, s.x[i + 1], s.y[i + 1])) {
            if (run_color) svg->Polyline(points, {*run_color, s.line_width, false});
            points.clear();
            continue;
          }
          const double value = 0.5 * (s.values[i] + s.values[i + 1]);
          const Color color = ColorMap((value - color_min) / (color_max - color_min));
          if (color != run_color) {
            if (run_color) svg->Polyline(points, {*run_color, s.line_width, false});
            points.clear();
            run_color = color;
          }
          if (points.empty()) points.emplace_back(axes.X(s.x[i]), axes.Y(s.y[i]));
          points.emplace_back(axes.X(s.x[i + 1]), axes.Y(s.y[i + 1]));
        }
        if (run_color) svg->Polyline(points, {*run_color, s.line_width, false});
        break;
      }
      case SeriesKind::kBars:
        for (size_t i = 0; i < n; ++i) {
          if (!Usable(figure, s.x[i], s.y[i])) continue;
          const double x0 = axes.X(s.x[i] - 0.5 * s.bar_width);
          const double x1 = axes.X(s.x[i] + 0.5 * s.bar_width);
          const double y0 = axes.Y(0.0);
          const double y1 = axes.Y(s.y[i]);
          PlotRectStyle bar = Filled(s.color);
          bar.outline = PlotStroke{kWhite, 0.5, false};
          svg->Rect(std::min(x0, x1), std::min(y0, y1), std::abs(x1 - x0), std::abs(y1 - y0), bar);
        }
        break;
    }
  }
}

void DrawReferenceLines(const Figure& figure, const Axes& axes, PlotCanvas* svg) {
  for (const ReferenceLine& line : figure.horizontal_lines) {
    const double py = axes.Y(line.value);
    svg->Line(axes.left, py, axes.left + axes.width, py, {line.color, 1.5, line.dashed});
    if (!line.label.empty()) {
      PlotTextStyle style = Anchored(TextAnchor::kEnd);
      style.color = line.color;
      svg->Text(axes.left + axes.width - 4, py - 4, line.label, style);
    }
  }
  for (const ReferenceLine& line : figure.vertical_lines) {
    if (figure.log_x && line.value <= 0.0) continue;
    const double px = axes.X(line.value);
    svg->Line(px, axes.top, px, axes.top + axes.height, {line.color, 1.5, line.dashed});
    if (!line.label.empty()) {
      PlotTextStyle style = Anchored(TextAnchor::kStart);
      style.color = line.color;
      svg->Text(px + 4, axes.top + 14, line.label, style);
    }
  }
}

void DrawLegend(const Figure& figure, const Axes& axes, PlotCanvas* svg) {
  std::vector<const Series*> entries;
  size_t longest = 0;
  for (const Series& s : figure.series) {
    if (s.label.empty()) continue;
    entries.push_back(&s);
    longest = std::max(longest, s.label.size());
  }
  if (entries.empty()) return;
  const double row = 17.0;
  const double box_width = 40.0 + kCharWidth * static_cast<double>(longest);
  const double box_height = 8.0 + row * static_cast<double>(entries.size());
  const double x0 =
      figure.legend_right ? axes.left + axes.width - box_width - 8.0 : axes.left + 8.0;
  const double y0 = axes.top + 8.0;
  PlotRectStyle box = Filled(kWhite);
  box.fill_opacity = 0.85;
  box.outline = PlotStroke{{0xbb, 0xbb, 0xbb}, 1.0, false};
  svg->Rect(x0, y0, box_width, box_height, box);
  for (size_t i = 0; i < entries.size(); ++i) {
    const Series& s = *entries[i];
    const double cy = y0 + 4.0 + row * (static_cast<double>(i) + 0.5);
    const double sx = x0 + 6.0;
    switch (s.kind) {
      case SeriesKind::kLine:
        svg->Line(sx, cy, sx + 22, cy, {s.color, s.line_width, s.dashed});
        break;
      case SeriesKind::kScatter: svg->Circle(sx + 11, cy, s.marker_radius, s.color); break;
      case SeriesKind::kColoredLine:
        for (int k = 0; k < 3; ++k) {
          svg->Line(sx + 7.33 * k, cy, sx + 7.33 * (k + 1), cy,
                    {ColorMap(0.1 + 0.4 * k), s.line_width + 0.5});
        }
        break;
      case SeriesKind::kBars: svg->Rect(sx + 4, cy - 6, 14, 12, Filled(s.color)); break;
    }
    svg->Text(sx + 28, cy + 4, s.label, Anchored(TextAnchor::kStart));
  }
}

void DrawColorBar(const Figure& figure, const Axes& axes, PlotCanvas* svg) {
  if (!HasColoredSeries(figure)) return;
  const auto [min, max] = ColorRange(figure);
  const double x = axes.left + axes.width + 18.0;
  const double bar_width = 14.0;
  const double step_height = axes.height / kColorBarSteps;
  for (int k = 0; k < kColorBarSteps; ++k) {
    // Top step holds the largest values.
    const double t = (kColorBarSteps - 1 - k + 0.5) / kColorBarSteps;
    svg->Rect(x, axes.top + k * step_height, bar_width, step_height + 0.3, Filled(ColorMap(t)));
  }
  svg->Rect(x, axes.top, bar_width, axes.height, Framed("colorbar"));
  const std::vector<double> ticks = LinearTicks(min, max, 5);
  const double step = TickStep(ticks);
  for (double t : ticks) {
    const double py = axes.top + axes.height - (t - min) / (max - min) * axes.height;
    svg->Line(x + bar_width, py, x + bar_width + 4, py, {kTickColor, 1.0});
    svg->Text(x + bar_width + 6, py + 4, FormatTick(t, step), Anchored(TextAnchor::kStart));
  }
  if (!figure.colorbar_label.empty()) {
    const double lx = x + bar_width + 58.0;
    const double ly = axes.top + 0.5 * axes.height;
    svg->Text(lx, ly, figure.colorbar_label, VerticalStyle());
  }
}

std::string FormatValue(double value, int decimals) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  return buffer;
}

}  // namespace

std::string Color::Hex() const {
  char buffer[8];
  std::snprintf(buffer, sizeof(buffer), "#%02x%02x%02x", r, g, b);
  return buffer;
}

Color ColorMap(double t) {
  // Samples of matplotlib's viridis at t = 0, 1/8, ..., 1, interpolated linearly.
  static constexpr std::array<std::array<double, 3>, 9> kStops = {{{68, 1, 84},
                                                                   {72, 40, 120},
                                                                   {62, 73, 137},
                                                                   {49, 104, 142},
                                                                   {38, 130, 142},
                                                                   {31, 158, 137},
                                                                   {53, 183, 121},
                                                                   {110, 206, 88},
                                                                   {253, 231, 37}}};
  if (!(t >= 0.0)) t = 0.0;
  if (t > 1.0) t = 1.0;
  const double position = t * (kStops.size() - 1);
  const size_t i = std::min(static_cast<size_t>(position), kStops.size() - 2);
  const double f = position - static_cast<double>(i);
  Color color;
  uint8_t* channels[3] = {&color.r, &color.g, &color.b};
  for (int c = 0; c < 3; ++c) {
    const double v = (1.0 - f) * kStops[i][c] + f * kStops[i + 1][c];
    *channels[c] = static_cast<uint8_t>(std::lround(std::clamp(v, 0.0, 255.0)));
  }
  return color;
}

Color PaletteColor(int index) {
  static constexpr std::array<Color, 8> kPalette = {{{31, 119, 180},
                                                     {255, 127, 14},
                                                     {44, 160, 44},
                                                     {214, 39, 40},
                                                     {148, 103, 189},
                                                     {140, 86, 75},
                                                     {227, 119, 194},
                                                     {127, 127, 127}}};
  const int n = static_cast<int>(kPalette.size());
  return kPalette[((index % n) + n) % n];
}

std::vector<double> LinearTicks(double min, double max, int target_count) {
  if (!std::isfinite(min) || !std::isfinite(max) || min > max) return {};
  if (min == max) return {min};
  target_count = std::max(target_count, 2);
  const double raw = (max - min) / target_count;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double step = 10.0 * magnitude;
  for (double factor : {1.0, 2.0, 5.0, 10.0}) {
    if (factor * magnitude >= raw * (1.0 - 1e-9)) {
      step = factor * magnitude;
      break;
    }
  }
  std::vector<double> ticks;
  const double tolerance = 1e-9 * step;
  for (int64_t k = static_cast<int64_t>(std::ceil((min - tolerance) / step));; ++k) {
    double value = static_cast<double>(k) * step;
    if (value > max + tolerance) break;
    if (std::abs(value) < tolerance) value = 0.0;
    ticks.push_back(value);
  }
  // A range narrower than its step from a tick holds fewer than two ticks:
  // use a finer step.
  if (ticks.size() < 2 && target_count < 1000) return LinearTicks(min, max, target_count * 2);
  return ticks;
}

std::vector<double> LogTicks(double min, double max) {
  if (!(min > 0.0) || !std::isfinite(max) || min > max) return {};
  const int first = static_cast<int>(std::floor(std::log10(min)));
  const int last = static_cast<int>(std::ceil(std::log10(max)));
  const bool fine = std::log10(max) - std::log10(min) < 3.0;
  std::vector<double> ticks;
  for (int e = first; e <= last; ++e) {
    const double base = std::pow(10.0, e);
    for (double factor : {1.0, 2.0, 5.0}) {
      if (factor != 1.0 && !fine) continue;
      const double value = factor * base;
      if (value >= min * (1.0 - 1e-9) && value <= max * (1.0 + 1e-9)) ticks.push_back(value);
    }
  }
  return ticks;
}

std::string FormatTick(double value, double step) {
  if (value == 0.0) return "0";
  char buffer[64];
  const double magnitude = std::abs(value);
  if (magnitude >= 1e6 || magnitude < 1e-4) {
    std::snprintf(buffer, sizeof(buffer), "%.6g", value);
    return buffer;
  }
  step = std::abs(step);
  int decimals = 0;
  if (step > 0.0 && step < 1.0) {
    decimals = static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  }
  decimals = std::clamp(decimals, 0, 8);
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  return buffer;
}

std::string XmlEscape(const std::string& text) {
  std::string escaped;
  escaped.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&': escaped += "&amp;"; break;
      case '<': escaped += "&lt;"; break;
      case '>': escaped += "&gt;"; break;
      case '"': escaped += "&quot;"; break;
      case '\'': escaped += "&#39;"; break;
      default: escaped += c;
    }
  }
  return escaped;
}

namespace {

void DrawFigure(const Figure& figure, PlotCanvas* canvas) {
  const Axes axes = ComputeAxes(figure);
  DrawAxes(figure, axes, canvas);
  DrawSeries(figure, axes, canvas);
  DrawReferenceLines(figure, axes, canvas);
  DrawColorBar(figure, axes, canvas);
  DrawLegend(figure, axes, canvas);
}

struct BarChartLayout {
  double left = 0.0, top = 0.0, row = 0.0, plot_width = 0.0, plot_height = 0.0, height = 0.0;
  double max_value = 1.0;
  double X(double v) const { return left + std::max(0.0, v) / max_value * plot_width; }
};

BarChartLayout LayOut(const BarChart& chart) {
  VIOSFM_CHECK_EQ(chart.names.size(), chart.values.size());
  BarChartLayout layout;
  size_t longest = 4;
  for (const std::string& name : chart.names) longest = std::max(longest, name.size());
  layout.left = std::clamp(14.0 + kCharWidth * static_cast<double>(longest), 60.0, 280.0);
  const double right = 80.0;  // the value text
  layout.top = chart.title.empty() ? kTopMarginPlain : kTopMarginTitle;
  layout.row = chart.bar_height + 6.0;
  layout.plot_height = std::max(layout.row, layout.row * static_cast<double>(chart.names.size()));
  layout.height = layout.top + layout.plot_height + 46.0;
  layout.plot_width = std::max(20.0, chart.width - layout.left - right);
  layout.max_value = 0.0;
  for (double v : chart.values) {
    if (std::isfinite(v)) layout.max_value = std::max(layout.max_value, v);
  }
  if (layout.max_value <= 0.0) layout.max_value = 1.0;
  return layout;
}

void DrawBarChart(const BarChart& chart, const BarChartLayout& layout, PlotCanvas* canvas) {
  const double left = layout.left, top = layout.top;
  const std::vector<double> ticks =
      LinearTicks(0.0, layout.max_value, std::max(2, static_cast<int>(layout.plot_width / 90.0)));
  const double step = TickStep(ticks);
  const double bottom = top + layout.plot_height;
  for (double t : ticks) {
    canvas->Line(layout.X(t), top, layout.X(t), bottom, {kGridColor, 1.0});
    canvas->Line(layout.X(t), bottom, layout.X(t), bottom + 5, {kTickColor, 1.0});
    canvas->Text(layout.X(t), bottom + 18, FormatTick(t, step), Anchored(TextAnchor::kMiddle));
  }
  for (size_t i = 0; i < chart.names.size(); ++i) {
    const double y = top + layout.row * static_cast<double>(i) + 3.0;
    const double v = std::isfinite(chart.values[i]) ? chart.values[i] : 0.0;
    PlotRectStyle bar = Filled(chart.color);
    bar.css_class = "bar";
    canvas->Rect(left, y, layout.X(v) - left, chart.bar_height, bar);
    canvas->Text(left - 6, y + chart.bar_height * 0.5 + 4, chart.names[i],
                 Anchored(TextAnchor::kEnd));
    canvas->Text(layout.X(v) + 4, y + chart.bar_height * 0.5 + 4,
                 FormatValue(v, chart.value_decimals), Anchored(TextAnchor::kStart));
  }
  canvas->Line(left, top, left, bottom, {kTickColor, 1.0});
  canvas->Line(left, bottom, left + layout.plot_width, bottom, {kTickColor, 1.0});
  if (!chart.title.empty()) canvas->Text(0.5 * chart.width, 22, chart.title, TitleStyle());
  if (!chart.value_label.empty()) {
    canvas->Text(left + 0.5 * layout.plot_width, bottom + 38, chart.value_label,
                 Anchored(TextAnchor::kMiddle));
  }
}

void WriteBytes(const std::filesystem::path& path, const std::vector<uint8_t>& bytes) {
  WriteFileAtomically(path, [&bytes](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
  });
}

}  // namespace

std::string RenderSvg(const Figure& figure) {
  SvgWriter svg(figure.width, figure.height);
  DrawFigure(figure, &svg);
  return svg.Finish();
}

std::string RenderSvg(const BarChart& chart) {
  const BarChartLayout layout = LayOut(chart);
  SvgWriter svg(chart.width, layout.height);
  DrawBarChart(chart, layout, &svg);
  return svg.Finish();
}

std::vector<uint8_t> RenderPng(const Figure& figure, double scale) {
  PngCanvas png(figure.width, figure.height, scale);
  DrawFigure(figure, &png);
  return png.Encode();
}

std::vector<uint8_t> RenderPng(const BarChart& chart, double scale) {
  const BarChartLayout layout = LayOut(chart);
  PngCanvas png(chart.width, layout.height, scale);
  DrawBarChart(chart, layout, &png);
  return png.Encode();
}

void WriteSvg(const std::filesystem::path& path, const Figure& figure) {
  const std::string text = RenderSvg(figure);
  WriteFileAtomically(path, [&text](std::ostream& out) { out << text; });
}

void WriteSvg(const std::filesystem::path& path, const BarChart& chart) {
  const std::string text = RenderSvg(chart);
  WriteFileAtomically(path, [&text](std::ostream& out) { out << text; });
}

void WritePng(const std::filesystem::path& path, const Figure& figure, double scale) {
  WriteBytes(path, RenderPng(figure, scale));
}

void WritePng(const std::filesystem::path& path, const BarChart& chart, double scale) {
  WriteBytes(path, RenderPng(chart, scale));
}

}  // namespace viosfm
