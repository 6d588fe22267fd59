// The drawing surface of the plots of report/svg_plot.h: the SVG writer and
// an OpenCV raster (PNG) implement it, so both draw the same figure from the
// same layout code. Coordinates are SVG pixels (y down).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "viosfm/report/svg_plot.h"

namespace viosfm {

struct PlotStroke {
  Color color;
  double width = 1.0;   // px
  bool dashed = false;  // 6 px on, 4 px off
};

enum class TextAnchor { kStart, kMiddle, kEnd };

struct PlotTextStyle {
  TextAnchor anchor = TextAnchor::kStart;
  double size = 12.0;  // px
  bool bold = false;
  bool vertical = false;       // rotated by -90 degrees about (x, y): reads upward
  std::optional<Color> color;  // default black
};

struct PlotRectStyle {
  std::optional<Color> fill;  // none when unset
  double fill_opacity = 1.0;  // < 1: blended over what is below
  std::optional<PlotStroke> outline;
  std::string css_class;  // SVG only: the rect's class attribute
};

class PlotCanvas {
 public:
  virtual ~PlotCanvas() = default;
  virtual void Line(double x1, double y1, double x2, double y2, const PlotStroke& stroke) = 0;
  virtual void Polyline(const std::vector<std::pair<double, double>>& points,
                        const PlotStroke& stroke) = 0;
  virtual void Rect(double x, double y, double width, double height,
                    const PlotRectStyle& style) = 0;
  virtual void Circle(double cx, double cy, double radius, const Color& fill) = 0;
  virtual void Text(double x, double y, const std::string& text, const PlotTextStyle& style) = 0;
};

// A white raster of width x height SVG pixels drawn at `scale` device pixels
// each; Encode() gives the PNG file's bytes.
class PngCanvas : public PlotCanvas {
 public:
  PngCanvas(double width, double height, double scale);
  ~PngCanvas() override;
  void Line(double x1, double y1, double x2, double y2, const PlotStroke& stroke) override;
  void Polyline(const std::vector<std::pair<double, double>>& points,
                const PlotStroke& stroke) override;
  void Rect(double x, double y, double width, double height, const PlotRectStyle& style) override;
  void Circle(double cx, double cy, double radius, const Color& fill) override;
  void Text(double x, double y, const std::string& text, const PlotTextStyle& style) override;
  std::vector<uint8_t> Encode() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace viosfm
