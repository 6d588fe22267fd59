#include "viosfm/report/svg_plot.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <map>
#include <regex>
#include <string>
#include <vector>

#include "viosfm/util/file_util.h"
#include "viosfm/util/string_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

// One element of an SVG text: its name and attributes.
struct Element {
  std::string name;
  std::map<std::string, std::string> attributes;
  double Number(const std::string& key) const {
    const auto it = attributes.find(key);
    EXPECT_NE(it, attributes.end()) << name << " has no attribute " << key;
    return it == attributes.end() ? std::nan("") : std::stod(it->second);
  }
};

// Parses the tags of `svg`, checking that they are balanced (every opening
// tag is closed, in order) and that every '<' starts a well-formed tag (text
// is escaped). Returns the opening / self-closing elements. A scanner, not
// std::regex: libstdc++'s regex recurses per character and overflows the
// stack on a long polyline under AddressSanitizer.
std::vector<Element> ParseBalanced(const std::string& svg) {
  const auto is_name = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == ':' ||
           c == '.';
  };
  const auto is_space = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  std::vector<Element> elements;
  std::vector<std::string> stack;
  size_t pos = 0;
  while ((pos = svg.find('<', pos)) != std::string::npos) {
    size_t i = pos + 1;
    const bool closing = i < svg.size() && svg[i] == '/';
    if (closing) ++i;
    size_t name_end = i;
    while (name_end < svg.size() && is_name(svg[name_end])) ++name_end;
    if (name_end == i || !std::isalpha(static_cast<unsigned char>(svg[i]))) {
      ADD_FAILURE() << "'<' at " << pos << " does not start a tag";
      return elements;
    }
    Element element;
    element.name = svg.substr(i, name_end - i);
    i = name_end;
    bool self_closing = false;
    while (true) {
      while (i < svg.size() && is_space(svg[i])) ++i;
      if (i >= svg.size()) {
        ADD_FAILURE() << "unterminated tag <" << element.name;
        return elements;
      }
      if (svg[i] == '>') {
        ++i;
        break;
      }
      if (svg.compare(i, 2, "/>") == 0) {
        self_closing = true;
        i += 2;
        break;
      }
      size_t key_end = i;
      while (key_end < svg.size() && is_name(svg[key_end])) ++key_end;
      const size_t value_end =
          svg.compare(key_end, 2, "=\"") == 0 ? svg.find('"', key_end + 2) : std::string::npos;
      if (closing || key_end == i || value_end == std::string::npos) {
        ADD_FAILURE() << "malformed tag <" << (closing ? "/" : "") << element.name;
        return elements;
      }
      const std::string value = svg.substr(key_end + 2, value_end - key_end - 2);
      EXPECT_EQ(value.find_first_of("<>"), std::string::npos) << "'<' or '>' in an attribute";
      element.attributes[svg.substr(i, key_end - i)] = value;
      i = value_end + 1;
    }
    pos = i;
    if (closing) {
      EXPECT_FALSE(stack.empty()) << "closing </" << element.name << "> without an opening tag";
      if (stack.empty()) break;
      EXPECT_EQ(stack.back(), element.name);
      stack.pop_back();
      continue;
    }
    if (!self_closing) stack.push_back(element.name);
    elements.push_back(std::move(element));
  }
  EXPECT_TRUE(stack.empty()) << "unclosed <" << (stack.empty() ? "" : stack.back()) << ">";
  return elements;
}

std::vector<Element> Named(const std::vector<Element>& elements, const std::string& name) {
  std::vector<Element> out;
  for (const Element& e : elements) {
    if (e.name == name) out.push_back(e);
  }
  return out;
}

Element PlotArea(const std::vector<Element>& elements) {
  for (const Element& e : elements) {
    const auto it = e.attributes.find("class");
    if (e.name == "rect" && it != e.attributes.end() && it->second == "plot-area") return e;
  }
  ADD_FAILURE() << "no plot-area rect";
  return {};
}

// The numbers of an SVG points list "x,y x,y ...".
std::vector<std::string_view> SplitPoints(const std::string& text) {
  return Split(text, " ,", /*skip_empty=*/true);
}

bool IsRound(double value, double step) {
  const double k = value / step;
  return std::abs(k - std::round(k)) < 1e-6;
}

TEST(LinearTicks, RoundStepsWithinRange) {
  struct Case {
    double min, max;
  };
  for (const Case& c : {Case{0.0, 1.0}, Case{-3.7, 12.2}, Case{0.013, 0.0871}, Case{1234, 98765},
                        Case{-0.5, -0.1}, Case{99.2, 100.4}}) {
    const std::vector<double> ticks = LinearTicks(c.min, c.max, 6);
    ASSERT_GE(ticks.size(), 2u) << c.min << " " << c.max;
    EXPECT_LE(ticks.size(), 13u);
    const double step = ticks[1] - ticks[0];
    const double mantissa = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
    EXPECT_THAT(mantissa,
                ::testing::AnyOf(::testing::DoubleNear(1.0, 1e-9), ::testing::DoubleNear(2.0, 1e-9),
                                 ::testing::DoubleNear(5.0, 1e-9)));
    for (size_t i = 0; i < ticks.size(); ++i) {
      EXPECT_TRUE(IsRound(ticks[i], step)) << ticks[i] << " step " << step;
      EXPECT_GE(ticks[i], c.min - 1e-9 * step);
      EXPECT_LE(ticks[i], c.max + 1e-9 * step);
      if (i > 0) {
        EXPECT_NEAR(ticks[i] - ticks[i - 1], step, 1e-9 * step);
      }
    }
    // No round tick was left out at either end.
    EXPECT_LT(ticks.front() - step, c.min);
    EXPECT_GT(ticks.back() + step, c.max);
  }
  EXPECT_THAT(LinearTicks(0.0, 1.0, 5),
              ::testing::ElementsAre(0.0, 0.2, 0.4, 0.6000000000000001, 0.8, 1.0));
}

TEST(LogTicks, PowersOfTen) {
  EXPECT_THAT(LogTicks(1.0, 500.0),
              ::testing::ElementsAre(1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0));
  EXPECT_THAT(LogTicks(0.5, 2e4), ::testing::ElementsAre(1.0, 10.0, 100.0, 1000.0, 10000.0));
}

TEST(FormatTick, DecimalsFollowStep) {
  EXPECT_EQ(FormatTick(0.6000000000000001, 0.2), "0.6");
  EXPECT_EQ(FormatTick(0.25, 0.05), "0.25");
  EXPECT_EQ(FormatTick(1500.0, 500.0), "1500");
  EXPECT_EQ(FormatTick(-2.0, 1.0), "-2");
  EXPECT_EQ(FormatTick(0.0, 0.1), "0");
  EXPECT_EQ(FormatTick(2e-5, 1e-5), "2e-05");
}

TEST(ColorMap, EndpointsAndClamping) {
  EXPECT_EQ(ColorMap(0.0), (Color{68, 1, 84}));
  EXPECT_EQ(ColorMap(1.0), (Color{253, 231, 37}));
  EXPECT_EQ(ColorMap(-3.0), ColorMap(0.0));
  EXPECT_EQ(ColorMap(7.0), ColorMap(1.0));
  EXPECT_EQ(ColorMap(std::nan("")), ColorMap(0.0));
  EXPECT_EQ(ColorMap(0.5), (Color{38, 130, 142}));
  EXPECT_EQ(ColorMap(1.0).Hex(), "#fde725");
  // Brightness increases along the map (viridis is perceptually ordered).
  double previous = -1.0;
  for (int i = 0; i <= 20; ++i) {
    const Color c = ColorMap(i / 20.0);
    const double luma = 0.299 * c.r + 0.587 * c.g + 0.114 * c.b;
    EXPECT_GT(luma, previous) << i;
    previous = luma;
  }
}

TEST(RenderSvg, DataExtremesMapToPlotAreaEdges) {
  Figure figure;
  figure.title = "A & B <test>";
  figure.x_label = "x (m)";
  figure.y_label = "y (m)";
  Series series;
  series.kind = SeriesKind::kScatter;
  series.label = "points";
  series.x = {-2.0, 3.0, 8.0};
  series.y = {0.5, -1.5, 4.5};
  figure.series.push_back(series);
  const std::string svg = RenderSvg(figure);
  EXPECT_NE(svg.find("A &amp; B &lt;test&gt;"), std::string::npos);
  const std::vector<Element> elements = ParseBalanced(svg);
  const Element area = PlotArea(elements);
  const double left = area.Number("x");
  const double top = area.Number("y");
  const double right = left + area.Number("width");
  const double bottom = top + area.Number("height");
  // The data circles (the legend's marker is the fourth).
  const std::vector<Element> circles = Named(elements, "circle");
  ASSERT_EQ(circles.size(), 4u);
  EXPECT_NEAR(circles[0].Number("cx"), left, 0.006);    // x min
  EXPECT_NEAR(circles[2].Number("cx"), right, 0.006);   // x max
  EXPECT_NEAR(circles[1].Number("cy"), bottom, 0.006);  // y min
  EXPECT_NEAR(circles[2].Number("cy"), top, 0.006);     // y max
  // The middle x is half-way.
  EXPECT_NEAR(circles[1].Number("cx"), 0.5 * (left + right), 0.006);
  // Tick labels are round numbers within the range.
  size_t numeric_labels = 0;
  const std::regex text(R"(<text[^>]*>(-?[0-9.]+)</text>)");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), text); it != std::sregex_iterator();
       ++it) {
    const double value = std::stod((*it)[1]);
    EXPECT_TRUE(IsRound(value, 0.5)) << value;
    EXPECT_GE(value, -2.0);
    EXPECT_LE(value, 8.0);
    ++numeric_labels;
  }
  EXPECT_GE(numeric_labels, 6u);
  // Deterministic.
  EXPECT_EQ(svg, RenderSvg(figure));
}

TEST(RenderSvg, LogAxisMapsDecadesEvenly) {
  Figure figure;
  figure.log_x = true;
  Series series;
  series.kind = SeriesKind::kScatter;
  series.x = {10.0, 100.0, 1000.0, -1.0};  // the non-positive x is left out
  series.y = {1.0, 2.0, 3.0, 4.0};
  figure.series.push_back(series);
  figure.horizontal_lines.push_back({2.5, "COLMAP", {200, 0, 0}, true});
  const std::vector<Element> elements = ParseBalanced(RenderSvg(figure));
  const Element area = PlotArea(elements);
  const std::vector<Element> circles = Named(elements, "circle");
  ASSERT_EQ(circles.size(), 3u);
  const double left = area.Number("x");
  const double right = left + area.Number("width");
  EXPECT_NEAR(circles[0].Number("cx"), left, 0.006);
  EXPECT_NEAR(circles[1].Number("cx"), 0.5 * (left + right), 0.006);
  EXPECT_NEAR(circles[2].Number("cx"), right, 0.006);
  // The reference line spans the plot area at y = 2.5 (between 1 and 3: mid-height).
  bool found = false;
  for (const Element& line : Named(elements, "line")) {
    if (line.attributes.at("stroke") != "#c80000") continue;
    found = true;
    EXPECT_NEAR(line.Number("x1"), left, 0.006);
    EXPECT_NEAR(line.Number("x2"), right, 0.006);
    EXPECT_NEAR(line.Number("y1"), area.Number("y") + 0.25 * area.Number("height"), 0.006);
  }
  EXPECT_TRUE(found);
}

TEST(RenderSvg, EqualAspectGivesSamePixelsPerUnit) {
  Figure figure;
  figure.equal_aspect = true;
  figure.width = 600;
  figure.height = 400;
  Series series;
  series.kind = SeriesKind::kScatter;
  series.x = {0.0, 1.0, 0.0};
  series.y = {0.0, 0.0, 1.0};
  figure.series.push_back(series);
  const std::vector<Element> circles = Named(ParseBalanced(RenderSvg(figure)), "circle");
  ASSERT_EQ(circles.size(), 3u);
  const double dx = circles[1].Number("cx") - circles[0].Number("cx");
  const double dy = circles[0].Number("cy") - circles[2].Number("cy");
  EXPECT_GT(dx, 10.0);
  EXPECT_NEAR(dx, dy, 0.02);
}

TEST(RenderSvg, ColoredLineUsesMapEndsAndDrawsColorBar) {
  Figure figure;
  figure.colorbar_label = "error (m)";
  Series series;
  series.kind = SeriesKind::kColoredLine;
  series.label = "estimate";
  for (int i = 0; i <= 100; ++i) {
    series.x.push_back(i);
    series.y.push_back(std::sin(i * 0.1));
    series.values.push_back(i * 0.01);
  }
  figure.series.push_back(series);
  const std::string svg = RenderSvg(figure);
  const std::vector<Element> elements = ParseBalanced(svg);
  const std::vector<Element> polylines = Named(elements, "polyline");
  ASSERT_GE(polylines.size(), 10u);
  // The first segment is near the map's start, the last near its end.
  EXPECT_EQ(polylines.front().attributes.at("stroke"), ColorMap(0.005).Hex());
  EXPECT_EQ(polylines.back().attributes.at("stroke"), ColorMap(0.995).Hex());
  bool has_colorbar = false;
  for (const Element& e : elements) {
    if (e.attributes.count("class") && e.attributes.at("class") == "colorbar") has_colorbar = true;
  }
  EXPECT_TRUE(has_colorbar);
  EXPECT_NE(svg.find(">error (m)</text>"), std::string::npos);
}

TEST(RenderSvg, BarsStartAtZero) {
  Figure figure;
  Series bars;
  bars.kind = SeriesKind::kBars;
  bars.x = {0.05, 0.15, 0.25};
  bars.y = {4.0, 10.0, 2.0};
  bars.bar_width = 0.1;
  figure.series.push_back(bars);
  figure.vertical_lines.push_back({0.5, "threshold 0.5", {200, 0, 0}, true});
  const std::vector<Element> elements = ParseBalanced(RenderSvg(figure));
  const Element area = PlotArea(elements);
  const double bottom = area.Number("y") + area.Number("height");
  std::vector<Element> bar_rects;
  for (const Element& e : Named(elements, "rect")) {
    if (e.attributes.count("stroke") && e.attributes.at("stroke") == "#ffffff") {
      bar_rects.push_back(e);
    }
  }
  ASSERT_EQ(bar_rects.size(), 3u);
  for (const Element& r : bar_rects) {
    EXPECT_NEAR(r.Number("y") + r.Number("height"), bottom, 0.011);
  }
  // Tallest bar reaches the top; the first bar's left edge is the plot's left.
  EXPECT_NEAR(bar_rects[1].Number("y"), area.Number("y"), 0.006);
  EXPECT_NEAR(bar_rects[0].Number("x"), area.Number("x"), 0.006);

  // With a margin, the bars still stand on the plot's bottom edge (y = 0 stays
  // the axis' start) and the tallest leaves the margin above it: y range
  // [0, 10 + 0.1 * 10].
  figure.margin_fraction = 0.1;
  const std::vector<Element> with_margin = ParseBalanced(RenderSvg(figure));
  const Element area2 = PlotArea(with_margin);
  std::vector<Element> bars2;
  for (const Element& e : Named(with_margin, "rect")) {
    if (e.attributes.count("stroke") && e.attributes.at("stroke") == "#ffffff") bars2.push_back(e);
  }
  ASSERT_EQ(bars2.size(), 3u);
  const double bottom2 = area2.Number("y") + area2.Number("height");
  EXPECT_NEAR(bars2[0].Number("y") + bars2[0].Number("height"), bottom2, 0.011);
  EXPECT_NEAR(bars2[1].Number("height"), area2.Number("height") * 10.0 / 11.0, 0.011);
}

TEST(RenderSvg, BarChartBarLengthsAreProportional) {
  BarChart chart;
  chart.title = "Stages";
  chart.names = {"features", "matching", "mapping"};
  chart.values = {2.0, 8.0, 4.0};
  const std::string svg = RenderSvg(chart);
  std::vector<Element> bars;
  for (const Element& e : Named(ParseBalanced(svg), "rect")) {
    if (e.attributes.count("class") && e.attributes.at("class") == "bar") bars.push_back(e);
  }
  ASSERT_EQ(bars.size(), 3u);
  EXPECT_NEAR(bars[1].Number("width") / bars[0].Number("width"), 4.0, 1e-3);
  EXPECT_NEAR(bars[2].Number("width") / bars[0].Number("width"), 2.0, 1e-3);
  EXPECT_NE(svg.find(">8.00</text>"), std::string::npos);
  EXPECT_NE(svg.find(">matching</text>"), std::string::npos);
}

TEST(RenderSvg, DenseLinesAreThinnedKeepingTheEnds) {
  Figure figure;
  Series line;
  for (int i = 0; i <= 20000; ++i) {
    line.x.push_back(i * 1e-4);
    line.y.push_back(i * 2e-4);
  }
  figure.series.push_back(line);
  const std::vector<Element> elements = ParseBalanced(RenderSvg(figure));
  const std::vector<Element> polylines = Named(elements, "polyline");
  ASSERT_EQ(polylines.size(), 1u);
  std::vector<double> numbers;
  for (std::string_view pair : SplitPoints(polylines[0].attributes.at("points"))) {
    numbers.push_back(std::stod(std::string(pair)));
  }
  const Element area = PlotArea(elements);
  const double left = area.Number("x");
  const double top = area.Number("y");
  const double right = left + area.Number("width");
  const double bottom = top + area.Number("height");
  ASSERT_GE(numbers.size(), 4u);
  // The diagonal of the plot area, at most one point a half pixel.
  const double diagonal = std::hypot(right - left, bottom - top);
  EXPECT_LE(numbers.size() / 2, static_cast<size_t>(diagonal / 0.5) + 2);
  EXPECT_GE(numbers.size() / 2, static_cast<size_t>(diagonal / 0.5 / 2));
  EXPECT_NEAR(numbers[0], left, 0.006);
  EXPECT_NEAR(numbers[1], bottom, 0.006);
  EXPECT_NEAR(numbers[numbers.size() - 2], right, 0.006);
  EXPECT_NEAR(numbers[numbers.size() - 1], top, 0.006);
}

TEST(WriteSvg, WritesRenderedText) {
  const std::filesystem::path folder = testing::MakeScratchFolder("svg_plot");
  Figure figure;
  figure.series.push_back({});
  figure.series.back().x = {0, 1};
  figure.series.back().y = {0, 1};
  WriteSvg(folder / "f.svg", figure);
  EXPECT_EQ(ReadTextFile(folder / "f.svg"), RenderSvg(figure));
}

}  // namespace
}  // namespace viosfm
